"""``make bench``: speed measurements, one module per area in this package.

Each area module defines ``AREA`` (str) and ``run() -> dict`` returning flat keys with units in
the name (``detailed_poses_per_s``, ``single_pose_latency_s``). ``python -m femcheck.bench [AREA ...]``
runs them, prints a table per area and writes ``reports/bench/<AREA>.json`` atomically.
"""
