"""Bench: what a new user waits for, measured on a fresh clone: the install, `make verify` with empty caches and
again with warm ones, `make verify` without MKL (pypardiso hidden) with its peak memory, and `make test`.

Steps (each in the clone, one after the other, never two at once; the 1-minute load average is sampled at the
end of each and stored beside it in ``load_average_by_figure``):

1. ``git clone`` of this repository's HEAD into a temporary folder, then ``make venv`` (timed: ``install_s``);
2. ``make verify`` with the clone's empty caches (``make_verify_cold_s``; ``ball_tilt_s`` is the tilt study's
   time from that run's manifest.json), then again (``make_verify_warm_s``: everything read from the caches);
3. ``make verify`` with empty caches in a fresh cache folder and ``FEMCHECK_NO_PARDISO=1`` (the path of machines
   without MKL, such as ARM: ``make_verify_nomkl_s``; ``nomkl_peak_gb``: the largest total resident memory of
   the command's process tree, sampled every 0.5 s);
4. ``make test`` (``test_suite_s``).

It takes about 15 min on the idle 2-core machine (most of it the install and the test suite).
``FEMCHECK_BENCH_VERIFY_STEPS`` (comma-separated: install, cold, warm, nomkl, test) runs a subset; the figures of
the steps left out are then absent from the JSON, never estimated.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

AREA = "verify"
ROOT = Path(__file__).resolve().parents[2]
STEPS = ("install", "cold", "warm", "nomkl", "test")
#: environment variables of this process that must not leak into the clone's runs (they would point it at
#: this checkout's caches or choices)
CLEARED = ("FEMCHECK_CACHE", "FEMCHECK_LINEAR_SOLVER", "FEMCHECK_SCHUR_METHOD", "FEMCHECK_SCHUR_MEMORY_GB",
           "FEMCHECK_NO_PARDISO",
           "FEMCHECK_NO_RESULT_CACHE", "PYTHONPATH", "VIRTUAL_ENV")


def _tree_rss_bytes(pid: int) -> int:
    """Resident memory of a process and all its descendants (bytes; 0 once it is gone)."""
    import psutil
    try:
        p = psutil.Process(pid)
        procs = [p] + p.children(recursive=True)
    except psutil.Error:
        return 0
    total = 0
    for q in procs:
        try:
            total += q.memory_info().rss
        except psutil.Error:
            pass
    return total


def timed(cmd: list[str], cwd: Path, env: dict, log: Path) -> dict:
    """Run ``cmd`` (output to ``log``); {seconds, rc, peak_gb (process tree), load_average (1 min, at the end)}."""
    peak = [0]
    with open(log, "wb") as fh:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=fh, stderr=subprocess.STDOUT)
        done = threading.Event()

        def sample():
            while not done.wait(0.5):
                peak[0] = max(peak[0], _tree_rss_bytes(proc.pid))
        th = threading.Thread(target=sample, daemon=True)
        th.start()
        rc = proc.wait()
        seconds = time.perf_counter() - t0
        done.set()
        th.join(timeout=2.0)
    return {"seconds": round(seconds, 1), "rc": rc, "peak_gb": round(peak[0] / 2**30, 2),
            "load_average": round(os.getloadavg()[0], 2)}


def _steps() -> tuple[str, ...]:
    raw = os.environ.get("FEMCHECK_BENCH_VERIFY_STEPS", "").strip()
    if not raw:
        return STEPS
    chosen = tuple(s.strip() for s in raw.split(",") if s.strip())
    bad = [s for s in chosen if s not in STEPS]
    if bad:
        from femcheck.errors import FemcheckError
        raise FemcheckError(f"FEMCHECK_BENCH_VERIFY_STEPS: {bad[0]!r}; expected some of {', '.join(STEPS)}")
    return chosen


def run() -> dict:
    steps = _steps()
    env = {k: v for k, v in os.environ.items() if k not in CLEARED}
    figures: dict = {}
    loads: dict = {}
    tmp = Path(tempfile.mkdtemp(prefix="femcheck-bench-verify-"))
    clone = tmp / "femcheck"
    logs = ROOT / "reports" / "bench" / "verify_logs"
    logs.mkdir(parents=True, exist_ok=True)
    try:
        subprocess.run(["git", "clone", "--quiet", str(ROOT), str(clone)], check=True)
        make = ["make"]
        if "install" in steps:
            r = timed(["make", "venv"], clone, env, logs / "install.log")
            _require(r, "make venv", logs / "install.log")
            figures["install_s"], loads["install_s"] = r["seconds"], r["load_average"]
        else:   # no install: the clone's code on this interpreter (its make stamp says installed)
            (clone / ".venv").mkdir()
            (clone / ".venv" / ".installed").touch()
            make = ["make", f"PY={sys.executable}"]
            env["PYTHONPATH"] = str(clone)
        if "cold" in steps:
            r = timed(make + ["verify"], clone, env, logs / "verify_cold.log")
            _require(r, "make verify (cold)", logs / "verify_cold.log", allow=(0, 1))
            figures["make_verify_cold_s"], loads["make_verify_cold_s"] = r["seconds"], r["load_average"]
            manifest = json.loads((clone / "reports" / "verify" / "manifest.json").read_text())
            figures["ball_tilt_s"] = manifest["fe"]["timings_s"]["ball_tilt_contact_fe"]
            loads["ball_tilt_s"] = r["load_average"]
            figures["verify_stage_s"] = {k: v for k, v in manifest["fe"]["timings_s"].items() if k != "vtu_files"}
        if "warm" in steps:
            r = timed(make + ["verify"], clone, env, logs / "verify_warm.log")
            _require(r, "make verify (warm)", logs / "verify_warm.log", allow=(0, 1))
            figures["make_verify_warm_s"], loads["make_verify_warm_s"] = r["seconds"], r["load_average"]
        if "nomkl" in steps:
            nomkl = {**env, "FEMCHECK_NO_PARDISO": "1", "FEMCHECK_CACHE": str(tmp / "cache_nomkl")}
            r = timed(make + ["verify"], clone, nomkl, logs / "verify_nomkl.log")
            _require(r, "make verify (no MKL)", logs / "verify_nomkl.log", allow=(0, 1))
            figures["make_verify_nomkl_s"], loads["make_verify_nomkl_s"] = r["seconds"], r["load_average"]
            figures["nomkl_peak_gb"], loads["nomkl_peak_gb"] = r["peak_gb"], r["load_average"]
        if "test" in steps:
            r = timed(make + ["test"], clone, env, logs / "test.log")
            _require(r, "make test", logs / "test.log")
            figures["test_suite_s"], loads["test_suite_s"] = r["seconds"], r["load_average"]
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    figures["load_average_by_figure"] = loads
    return figures


def _require(r: dict, what: str, log: Path, allow=(0,)) -> None:
    """A step that failed has no figure: stop with the log's name (``make verify`` exits 1 on a failed check:
    its time still counts, the verdict is the verify's own business)."""
    if r["rc"] not in allow:
        raise RuntimeError(f"{what} exited {r['rc']} after {r['seconds']} s; see {log}")
