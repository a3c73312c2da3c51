"""Bench: the analytical chain models — batched throughput (poses/s) and single-pose latency.

Measured on one core (numba kernels are serial; BLAS threads are not used in the hot path).
Poses are random TCP positions in the 50 mm test cube with small random rotations, loaded by the
detailed test load along x.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

AREA = "analytical"
CASE = Path("cases/haptic_6psu.toml")


def _throughput(fn, poses, repeats: int = 3) -> float:
    fn(poses[:64])  # compile / warm caches
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn(poses)
        best = min(best, time.perf_counter() - t0)
    return poses.shape[0] / best


def _latency(fn, poses, n: int = 2000) -> tuple[float, float]:
    fn(poses[:1])
    samples = np.empty(n)
    for i in range(n):
        t0 = time.perf_counter()
        fn(poses[i % poses.shape[0]: i % poses.shape[0] + 1])
        samples[i] = time.perf_counter() - t0
    return float(np.median(samples)), float(np.percentile(samples, 99))


def run() -> dict:
    import femcheck
    from femcheck.chain import evaluate
    case = femcheck.load_case(CASE)
    rng = np.random.default_rng(1)
    n = 100_000
    centre = femcheck.test_points(case)[0]
    poses = np.tile(centre, (n, 1))
    poses[:, :3] += rng.uniform(-0.025, 0.025, (n, 3))
    poses[:, 3:] += rng.uniform(-0.02, 0.02, (n, 3))
    W = np.array([case.loads.detailed_test_N, 0, 0, 0, 0, 0])
    out = {"poses_in_batch": n}
    for model in ("detailed", "simplified"):
        for joints in ("rigid", "released"):
            fn = lambda P, m=model, j=joints: evaluate(case, P, W, model=m, joints=j)
            key = f"{model}_{joints}"
            out[f"{key}_poses_per_s"] = round(_throughput(fn, poses), 1)
            med, p99 = _latency(fn, poses)
            out[f"{key}_single_pose_latency_s"] = med
            out[f"{key}_single_pose_latency_p99_s"] = p99
    # the headline figures are the paper's idealization (case default: rigid)
    out["detailed_poses_per_s"] = out[f"detailed_{case.model.joint_rotations}_poses_per_s"]
    out["single_pose_latency_s"] = out[f"detailed_{case.model.joint_rotations}_single_pose_latency_s"]
    fn_np = lambda P: evaluate(case, P, W, model="detailed", backend="numpy")
    out["detailed_rigid_numpy_reference_poses_per_s"] = round(_throughput(fn_np, poses[:10_000], repeats=1), 1)
    return out
