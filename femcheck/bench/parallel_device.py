"""Bench ``parallel_device``: the general parallel-device model on the 6-PSU, the hexapod and the Delta.

On poses of the 6-PSU cube (4,000 poses, TCP shifted up to ±25 mm), detailed model, both joint idealizations:
poses/s of the five-element chain model ``femcheck.chain.evaluate`` (the general model on the legs of
``cases/haptic_6psu.toml``, with the parameters derived from its layout tables), of the general model's compiled
path (default) with and without its inverse kinematics, and of its numpy reference path. The dedicated 6-PSU kernel
that the general model replaced is gone: its throughput in this bench's last run with it
(:data:`RETIRED_KERNEL_POSES_PER_S`, recorded on the same machine, poses, load and timing method) is the reference
of ``psu6_chain_over_retired_kernel_throughput_ratio_<joints>`` and of ``general_vs_dedicated_throughput_ratio``
(the smaller ratio general with IK / recorded kernel of the two idealizations). A ratio to a recorded figure moves
with the machine's load as well (the interleaved ratios it replaces did not). "with IK" is the default call (no
state given): inverse kinematics and chain model in one compiled call (the fused kernel); "without" is the chain
kernel on a state solved beforehand. The timings are interleaved (chain, general, general with IK, in turn, best
of ``REPEAT`` rounds) so that a busy shared machine loads them alike, and measured in CPU time of the process
(``time.process_time``; wall time counted the other jobs' share of the two cores). Then the closed-form inverse
kinematics against the numeric one on the same poses: largest joint-value difference (m or rad) and relative K_T
difference (6-PSU), joint values (hexapod, rotated poses), joint values and relative K_T difference (Delta, R*-U-U,
random poses of its cube), and the Delta's inverse kinematics alone, closed form against the compiled
Gauss-Newton (``delta_3ruu_numeric_over_closed_form_ik_time_ratio``: how many times faster the closed form is).
Then the hexapod and the Delta: poses/s of the detailed model (compiled and numpy, with inverse kinematics),
and the beam FE's largest relative difference from it at the nine test points (both levels, both idealizations).
"""
from __future__ import annotations

import time

import numpy as np

AREA = "parallel_device"
N_POSES = 4000
REPEAT = 15
#: poses/s of the retired dedicated 6-PSU kernel in this bench (reports/bench/parallel_device.json, its last run
#: with the kernel: ``psu6_kernel_<joints>_poses_per_s``, AMD EPYC, 2 CPUs, load average 0.45)
RETIRED_KERNEL_POSES_PER_S = {"rigid": 54710, "released": 262719}


def _timed(fn):
    """CPU seconds of this process spent in ``fn`` (every path timed here is single-threaded: numba kernels
    and numpy with one BLAS thread), so that time the shared machine gives to other jobs does not count."""
    t = time.process_time()
    fn()
    return time.process_time() - t


def _rates(fns: dict, n: int, repeat: int = REPEAT) -> dict:
    """poses/s of each function, best of ``repeat`` interleaved rounds."""
    best = {k: np.inf for k in fns}
    for _ in range(repeat):
        for k, fn in fns.items():
            best[k] = min(best[k], _timed(fn))
    return {k: n / v for k, v in best.items()}


def run() -> dict:
    from femcheck.case import load_case
    from femcheck.chain import evaluate as evaluate_6psu
    from femcheck.kinematics.psu6 import test_points as psu_points
    from femcheck.parallel.beam_fe import device_fe_stiffness
    from femcheck.parallel.chain_model import evaluate
    from femcheck.parallel.compiled import solve_legs_compiled
    from femcheck.parallel.device import test_points
    from femcheck.parallel.leg_kinematics import solve_legs

    out: dict = {"poses": N_POSES}
    c6 = cp = load_case("cases/haptic_6psu.toml")
    rng = np.random.default_rng(0)
    P = np.tile(psu_points(c6)[0], (N_POSES, 1))
    P[:, :3] += rng.uniform(-0.025, 0.025, (N_POSES, 3))
    W = [0, 0, c6.loads.detailed_test_N, 0, 0, 0]
    evaluate_6psu(c6, P[:10], W)  # compile (or load the cached machine code)
    evaluate(cp.device, P[:10], W)
    state = solve_legs(cp.device, P)
    state_np = solve_legs(cp.device, P, backend="numpy")
    K_ref = {}
    for joints in ("rigid", "released"):
        r = _rates({"chain": lambda: evaluate_6psu(c6, P, W, joints=joints),
                    "general": lambda: evaluate(cp.device, P, W, joints=joints, state=state),
                    "general_ik": lambda: evaluate(cp.device, P, W, joints=joints)}, N_POSES)
        r_np = _rates({"numpy": lambda: evaluate(cp.device, P, W, joints=joints, state=state_np, backend="numpy"),
                       "numpy_ik": lambda: evaluate(cp.device, P, W, joints=joints, backend="numpy")}, N_POSES, 1)
        kernel = RETIRED_KERNEL_POSES_PER_S[joints]
        out[f"psu6_chain_{joints}_poses_per_s"] = round(r["chain"])
        out[f"retired_kernel_{joints}_poses_per_s"] = kernel
        out[f"general_{joints}_poses_per_s"] = round(r["general"])
        out[f"general_{joints}_with_ik_poses_per_s"] = round(r["general_ik"])
        out[f"general_numpy_{joints}_poses_per_s"] = round(r_np["numpy"])
        out[f"general_numpy_{joints}_with_ik_poses_per_s"] = round(r_np["numpy_ik"])
        out[f"psu6_chain_over_retired_kernel_throughput_ratio_{joints}"] = round(r["chain"] / kernel, 3)
        K_ref[joints] = evaluate(cp.device, P, W, joints=joints).K
        out["general_vs_dedicated_throughput_ratio"] = min(out.get("general_vs_dedicated_throughput_ratio", np.inf),
                                                           round(r["general_ik"] / kernel, 3))
    # the closed-form inverse kinematics against the numeric one (compiled Gauss-Newton) on the same poses
    numeric = solve_legs_compiled(cp.device, P, numeric_only=True)
    out["closed_form_vs_numeric_ik_max_abs_dq_psu6"] = max(float(np.abs(a.q - b.q).max())
                                                          for a, b in zip(state.legs, numeric.legs))
    out["closed_form_vs_numeric_ik_max_rel_dK_psu6"] = max(
        float(np.abs(evaluate(cp.device, P, W, joints=j, state=state).K
                     - evaluate(cp.device, P, W, joints=j, state=numeric).K).max() / np.abs(K_ref[j]).max())
        for j in ("rigid", "released"))
    out["general_ik_poses_per_s"] = round(_rates({"ik": lambda: solve_legs(cp.device, P)}, N_POSES)["ik"])
    out["general_numpy_ik_poses_per_s"] = round(_rates({"ik": lambda: solve_legs(cp.device, P, backend="numpy")},
                                                       N_POSES, 1)["ik"])
    for name in ("hexapod_6ups", "delta_3ruu"):
        case = load_case(f"cases/{name}.toml")
        Pd = np.tile(test_points(case), (N_POSES // 9, 1))
        evaluate(case.device, Pd[:10], [0, 0, 10, 0, 0, 0])
        r = _rates({"c": lambda: evaluate(case.device, Pd, [0, 0, 10, 0, 0, 0])}, len(Pd), 3)
        r_np = _rates({"np": lambda: evaluate(case.device, Pd, [0, 0, 10, 0, 0, 0], backend="numpy")}, len(Pd), 1)
        out[f"{name}_detailed_with_ik_poses_per_s"] = round(r["c"])
        if name == "hexapod_6ups":
            Ph = Pd.copy()
            Ph[:, :3] += rng.uniform(-0.01, 0.01, (len(Ph), 3))
            Ph[:, 3:] += rng.uniform(-0.05, 0.05, (len(Ph), 3))
            a, b = solve_legs(case.device, Ph), solve_legs_compiled(case.device, Ph, numeric_only=True)
            out["closed_form_vs_numeric_ik_max_abs_dq_hexapod"] = max(float(np.abs(x.q - y.q).max())
                                                                      for x, y in zip(a.legs, b.legs))
        if name == "delta_3ruu":
            # the R*-U-U closed form against the compiled Gauss-Newton, random poses of the test cube
            Pr = np.tile(test_points(case)[0], (N_POSES, 1))
            Pr[:, :3] += rng.uniform(-0.02, 0.02, (N_POSES, 3))
            a, b = solve_legs(case.device, Pr), solve_legs_compiled(case.device, Pr, numeric_only=True)
            out["closed_form_vs_numeric_ik_max_abs_dq_delta"] = max(float(np.abs(x.q - y.q).max())
                                                                    for x, y in zip(a.legs, b.legs))
            out["closed_form_vs_numeric_ik_max_rel_dK_delta"] = max(
                float(np.abs(evaluate(case.device, Pr, [0, 0, 10, 0, 0, 0], joints=j, state=a).K
                             - evaluate(case.device, Pr, [0, 0, 10, 0, 0, 0], joints=j, state=b).K).max()
                      / np.abs(evaluate(case.device, Pr, [0, 0, 10, 0, 0, 0], joints=j, state=b).K).max())
                for j in ("rigid", "released"))
            r_ik = _rates({"closed": lambda: solve_legs(case.device, Pr),
                           "numeric": lambda: solve_legs_compiled(case.device, Pr, numeric_only=True)}, N_POSES)
            out["delta_3ruu_closed_form_ik_poses_per_s"] = round(r_ik["closed"])
            out["delta_3ruu_numeric_ik_poses_per_s"] = round(r_ik["numeric"])
            out["delta_3ruu_numeric_over_closed_form_ik_time_ratio"] = round(r_ik["closed"] / r_ik["numeric"], 2)
        out[f"{name}_detailed_numpy_with_ik_poses_per_s"] = round(r_np["np"])
        worst = 0.0
        for model in ("simplified", "detailed"):
            for joints in ("rigid", "released"):
                r = evaluate(case.device, test_points(case), [0, 0, 10, 0, 0, 0], model=model, joints=joints)
                K = device_fe_stiffness(case.device, test_points(case), model=model, joints=joints,
                                        hertz_stiffness=r.hertz_stiffness, state=r.state)
                worst = max(worst, float(np.abs(K - r.K).max() / np.abs(r.K).max()))
        out[f"{name}_beam_fe_max_rel_dK"] = worst
    return out
