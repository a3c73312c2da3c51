"""Bench ``sweep``: analytical sweep throughput and the local-pool overhead (issue 8).

1. One full analytical sweep of the detailed model on the reference case: an LHS over two element
   parameters (guideway width, link outer diameter), 111,112 samples x 9 cube points = 1,000,008
   sample-points (each = 3 load cases +x, +y, +z, so 3,000,024 chain evaluations), on the default local
   process pool (one worker per CPU), through the whole pipeline (design, keys, tasks, Parquet chunks,
   final table). Target: <= 60 s. ``FEMCHECK_BENCH_SWEEP_POINTS`` shrinks it for a quick check (the
   figures then say how many sample-points were run; nothing is extrapolated).
2. The same kind of sweep at 20,007 sample-points in this process (``jobs = 0``), and on a pool of 1 and
   of 2 workers: the pool overhead (process start-up, pickling, result transfer) is the difference. The
   in-process run also gives the CPU seconds per million sample-points, a per-core cost that does not
   depend on what else runs on the machine (the wall-clock figures do: the load average is recorded).

FE sweeps are not available until the whole-device FE verification exists, so there is no FE figure.
"""
from __future__ import annotations

import os
import tempfile
import time

AREA = "sweep"

_PARAMS = ["guideway.width_radial_m=0.010:0.020", "proximal_link.outer_diameter_m=0.006:0.010"]


def _sweep(case, ranges, samples, jobs, out):
    from femcheck.sweep.run import run_sweep
    t0, c0 = time.perf_counter(), time.process_time()
    o = run_sweep(case, ranges, out, design="lhs", samples=samples, seed=1, model="detailed", jobs=jobs)
    return time.perf_counter() - t0, o, time.process_time() - c0


def run() -> dict:
    from femcheck.case import load_case
    from femcheck.sweep.parameters import parse_params
    case = load_case("cases/haptic_6psu.toml")
    ranges = parse_params(case, _PARAMS)
    n_pts = 9
    target = int(os.environ.get("FEMCHECK_BENCH_SWEEP_POINTS", "1000000"))
    big = -(-target // n_pts)
    cpus = os.cpu_count() or 1
    figures = {}
    with tempfile.TemporaryDirectory(prefix="femcheck-bench-sweep-") as tmp:
        _sweep(case, ranges, 4, 0, f"{tmp}/warm")  # load the compiled kernel in this process
        small = 2223
        for label, jobs in (("in_process", 0), ("pool_1_worker", 1), ("pool_2_workers", 2)):
            wall, o, cpu = _sweep(case, ranges, small, jobs, f"{tmp}/small_{label}")
            figures[f"small_{label}_wall_s"] = round(wall, 3)
            if jobs == 0:  # CPU time of this process only: a per-core cost that other users' load hardly changes
                figures["in_process_cpu_s_per_1e6_sample_points"] = round(cpu / (small * n_pts) * 1e6, 1)
        figures["small_sample_points"] = small * n_pts
        figures["pool_1_worker_overhead_s"] = round(figures["small_pool_1_worker_wall_s"] - figures["small_in_process_wall_s"], 3)
        figures["pool_2_workers_speedup"] = round(figures["small_in_process_wall_s"] / figures["small_pool_2_workers_wall_s"], 3)
        wall, o, _ = _sweep(case, ranges, big, None, f"{tmp}/big")
        t = o.manifest["timing"]
        figures.update({
            "sample_points": big * n_pts,
            "chain_evaluations": big * n_pts * len(case.loads.directions),
            "workers": t["workers"],
            "cpu_count": cpus,
            "sweep_wall_s": round(wall, 2),
            "compute_wall_s": round(t["compute_wall_s"], 2),
            "sample_points_per_s": round(big * n_pts / wall, 1),
            "chain_evaluations_per_s": round(big * n_pts * len(case.loads.directions) / wall, 1),
            "target_1e6_points_in_60_s_met": bool(big * n_pts >= 1_000_000 and wall <= 60.0),
            "load_average_1min_at_end": round(os.getloadavg()[0], 2),
            "fe_sweep": "not available: needs the whole-device FE verification (make verify)",
        })
    return figures
