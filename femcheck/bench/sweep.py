"""Bench ``sweep``: analytical sweep throughput, the local-pool overhead and the FE sweep wall time.

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
3. An FE sweep (``--model fe``): :data:`FE_SAMPLES` LHS samples of the link outer diameter x P0, coarse
   mesh, detailed FE level, one sample per task, on a pool of 1 and of 2 workers ("FE sweep wall time
   with 1 and 2 workers"). ``fe_sample_s_mean`` is the 1-worker wall time per sample (pool start-up
   included). Each run starts from its own empty mesh cache (``FEMCHECK_CACHE``), as a fresh sweep
   would, so both pay the same meshing. ``FEMCHECK_BENCH_FE_SAMPLES`` changes the sample count.
"""
from __future__ import annotations

import os
import tempfile
import time

AREA = "sweep"

_PARAMS = ["guideway.width_radial_m=0.010:0.020", "proximal_link.outer_diameter_m=0.006:0.010"]
#: FE part: one parameter (the link tube, which dominates the FE cost), one point, coarse mesh
_FE_PARAMS = ["proximal_link.outer_diameter_m=0.006:0.008"]
FE_SAMPLES = 4
FE_POINTS = ("P0",)


def _sweep(case, ranges, samples, jobs, out):
    from femcheck.sweep.run import run_sweep
    t0, c0 = time.perf_counter(), time.process_time()
    o = run_sweep(case, ranges, out, design="lhs", samples=samples, seed=1, model="detailed", jobs=jobs)
    return time.perf_counter() - t0, o, time.process_time() - c0


def fe_sweep_figures(case, tmp: str, samples: int = FE_SAMPLES) -> dict:
    """Wall time of an FE sweep of ``samples`` samples x :data:`FE_POINTS` on 1 and on 2 workers."""
    from femcheck.sweep.parameters import parse_params
    from femcheck.sweep.run import run_sweep
    ranges = parse_params(case, _FE_PARAMS)
    walls, n_ok = {}, []
    saved = os.environ.get("FEMCHECK_CACHE")
    try:
        for workers in (1, 2):
            os.environ["FEMCHECK_CACHE"] = f"{tmp}/fe_meshes_{workers}"  # cold cache; forked workers inherit it
            t0 = time.perf_counter()
            o = run_sweep(case, ranges, f"{tmp}/fe_{workers}", design="lhs", samples=samples, seed=1, model="fe",
                          points=FE_POINTS, jobs=workers, fe_level="detailed", mesh="coarse")
            walls[workers] = time.perf_counter() - t0
            n_ok.append(int(o.manifest["sample_points_ok"]))
    finally:
        if saved is None:
            os.environ.pop("FEMCHECK_CACHE", None)
        else:
            os.environ["FEMCHECK_CACHE"] = saved
    return {
        "fe_sweep_samples": samples,
        "fe_sweep_points": len(FE_POINTS),
        "fe_sweep_mesh": "coarse",
        "fe_sweep_level": "detailed",
        "fe_sweep_sample_points_ok": min(n_ok),  # of each run
        "fe_sweep_wall_s_1_worker": round(walls[1], 2),
        "fe_sweep_wall_s_2_workers": round(walls[2], 2),
        "fe_sweep_speedup_2_workers": round(walls[1] / walls[2], 3),
        "fe_sample_s_mean": round(walls[1] / samples, 2),
        "fe_load_average_1min_at_end": round(os.getloadavg()[0], 2),
    }


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
        })
        figures.update(fe_sweep_figures(case, tmp, int(os.environ.get("FEMCHECK_BENCH_FE_SAMPLES", FE_SAMPLES))))
    return figures
