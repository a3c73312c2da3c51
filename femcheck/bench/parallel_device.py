"""Bench ``parallel_device``: the general parallel-device model (issue 19) against the 6-PSU kernel.

On the same poses of the 6-PSU cube (4,000 poses, TCP shifted up to ±25 mm), the 6-PSU numba kernel on
``cases/haptic_6psu.toml`` and the general model on ``cases/haptic_6psu_legs.toml`` (the same device, leg by
leg): poses/s of each (the general model with and without its inverse kinematics), their ratio (the issue's
target for moving the 6-PSU onto the general model is ≤ 1.3), and the largest relative K_T difference.
Then the hexapod and the Delta: poses/s of the detailed model, and the beam FE's largest relative difference
from it at the nine test points (both levels, both idealizations).
"""
from __future__ import annotations

import time

import numpy as np

AREA = "parallel_device"
N_POSES = 4000


def _rate(fn, n, repeat=3):
    best = min(_timed(fn) for _ in range(repeat))
    return n / best


def _timed(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def run() -> dict:
    from femcheck.case import load_case
    from femcheck.chain import evaluate as evaluate_6psu
    from femcheck.kinematics.psu6 import test_points as psu_points
    from femcheck.parallel.beam_fe import device_fe_stiffness
    from femcheck.parallel.chain_model import evaluate
    from femcheck.parallel.device import test_points
    from femcheck.parallel.leg_kinematics import solve_legs

    out: dict = {"poses": N_POSES}
    c6, cp = load_case("cases/haptic_6psu.toml"), load_case("cases/haptic_6psu_legs.toml")
    rng = np.random.default_rng(0)
    P = np.tile(psu_points(c6)[0], (N_POSES, 1))
    P[:, :3] += rng.uniform(-0.025, 0.025, (N_POSES, 3))
    W = [0, 0, c6.loads.detailed_test_N, 0, 0, 0]
    evaluate_6psu(c6, P[:10], W)  # compile
    state = solve_legs(cp.device, P)
    for joints in ("rigid", "released"):
        k6 = _rate(lambda: evaluate_6psu(c6, P, W, joints=joints), N_POSES)
        kg = _rate(lambda: evaluate(cp.device, P, W, joints=joints, state=state), N_POSES)
        kik = _rate(lambda: evaluate(cp.device, P, W, joints=joints), N_POSES, repeat=1)
        a, b = evaluate_6psu(c6, P, W, joints=joints), evaluate(cp.device, P, W, joints=joints, state=state)
        out[f"psu6_kernel_{joints}_poses_per_s"] = round(k6)
        out[f"general_{joints}_poses_per_s"] = round(kg)
        out[f"general_{joints}_with_ik_poses_per_s"] = round(kik)
        out[f"general_over_kernel_time_ratio_{joints}"] = round(k6 / kik, 2)
        out[f"general_vs_kernel_max_rel_dK_{joints}"] = float(np.abs(a.K - b.K).max() / np.abs(a.K).max())
    for name in ("hexapod_6ups", "delta_3ruu"):
        case = load_case(f"cases/{name}.toml")
        Pd = np.tile(test_points(case), (N_POSES // 9, 1))
        out[f"{name}_detailed_with_ik_poses_per_s"] = round(_rate(lambda: evaluate(case.device, Pd, [0, 0, 10, 0, 0, 0]),
                                                                  len(Pd), repeat=1))
        worst = 0.0
        for model in ("simplified", "detailed"):
            for joints in ("rigid", "released"):
                r = evaluate(case.device, test_points(case), [0, 0, 10, 0, 0, 0], model=model, joints=joints)
                K = device_fe_stiffness(case.device, test_points(case), model=model, joints=joints,
                                        hertz_stiffness=r.hertz_stiffness, state=r.state)
                worst = max(worst, float(np.abs(K - r.K).max() / np.abs(r.K).max()))
        out[f"{name}_beam_fe_max_rel_dK"] = worst
    return out
