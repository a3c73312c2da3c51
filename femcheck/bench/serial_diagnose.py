"""Bench area ``serial_diagnose``: the self-weight diagnosis of serial robots.

Figures:

* ``tree19_500poses_2markers_cpu_s`` (CPU seconds of this process, the figure the 10 s budget is about) and
  ``tree19_500poses_2markers_wall_s``: one diagnosis of 500 poses x 2 markers of a 19-joint tree (torso 3, two
  7-joint arms, head 2), every single cause and every pair weighed, with 5-fold cross-validation;
  ``tree19_cpu_budget_s`` the budget and ``tree19_within_budget`` whether the CPU time meets it;
* the confusion matrix on generated robots (:func:`scenarios`): a torso with two 7-joint arms and a 6-joint
  industrial arm, random geometric errors (1 mm, 0.2 deg), random sensor frame, Gaussian noise, hidden effects
  sized by the RMS marker motion they cause (``1.5 sigma``: near the detection limit; ``5 sigma``: above it), the
  clean robot, two-cause mixtures and four effects outside the vocabulary. ``*_rate`` keys are shares of the
  scenario group; ``confusion.<truth> -> <answer>_n`` the counts of the confusion matrix, ``wrong`` the
  scenarios answered wrongly (names joined by "; ").
"""
from __future__ import annotations

import time
from collections import Counter

import numpy as np

AREA = "serial_diagnose"
N_POSES = 250
#: CPU seconds one 500-pose, 19-joint, 2-marker diagnosis may take
CPU_BUDGET_S = 10.0


def scenarios(seeds=(0, 1)):
    """(name, robot, truth ids, truth joints, simulate kwargs) of the confusion-matrix study."""
    from femcheck.robot.simulate import humanoid_case, industrial_case, scaled
    out = []
    for seed in seeds:
        rng = np.random.default_rng(100 + seed)
        hum, _ = humanoid_case(seed, head=False, sigma_m=2e-4)
        ind, _ = industrial_case(seed, sigma_m=5e-5, springs=True)
        for robot, case, sig in (("humanoid17", hum, 2e-4), ("industrial6", ind, 5e-5)):
            arm = "r" if rng.uniform() < 0.5 else "l"
            if robot == "humanoid17":
                k0 = int(rng.integers(1, 4))
                tors = [f"{arm}{k}" for k in range(k0, k0 + 3)]
                back = [f"{arm}{int(rng.integers(1, 5))}"]
            else:
                k0 = int(rng.integers(2, 4))
                tors = [f"j{k}" for k in (k0, k0 + 1)]
                back = [f"j{int(rng.integers(2, 4))}"]
            singles = {"joint_torsion_compliance": {j: 1.0 for j in tors},
                       "joint_tilt_compliance": {"all": 1.0},
                       "gear_clearance": {j: 1.0 for j in back},
                       "link_bending_compliance": {"all": 1.0}}
            if robot == "industrial6":
                singles["mass_scale"] = {"all": 1.0}
            joints_of = {"joint_torsion_compliance": tors, "gear_clearance": back}
            out.append((f"{robot}/clean", robot, case, (), {}, dict(effects={}, sigma_m=sig)))
            for level, k in (("limit", 1.5), ("above", 5.0)):
                for cid, eff in singles.items():
                    e = scaled(case, {cid: eff}, k * sig)
                    out.append((f"{robot}/{cid}/{level}", robot, case, (cid,), {cid: joints_of.get(cid, [])},
                                dict(effects=e, sigma_m=sig)))
            pair = {**scaled(case, {"joint_torsion_compliance": singles["joint_torsion_compliance"]}, 5 * sig),
                    **scaled(case, {"gear_clearance": singles["gear_clearance"]}, 5 * sig)}
            out.append((f"{robot}/torsion+clearance", robot, case, ("joint_torsion_compliance", "gear_clearance"),
                        joints_of, dict(effects=pair, sigma_m=sig)))
            for name, mag in (("drift", 40 * sig / N_POSES), ("sensor_scale", 8 * sig / 0.5), ("compliant_base", None),
                              ("cross_talk", 8 * sig / 0.5)):
                if name == "compliant_base":
                    mag = 8 * sig / (0.6 * 9.81 * float(case.tree.mass.sum()) * 0.3 * 0.5)
                out.append((f"{robot}/foreign:{name}", robot, case, ("unexplained",), {}, dict(foreign={name: mag}, sigma_m=sig)))
    return out


def run_scenario(sc, seed=0):
    from femcheck.robot.diagnosis import diagnose_tree
    from femcheck.robot.simulate import simulate_positions
    name, robot, case, truth, joints, kw = sc
    data, _ = simulate_positions(case, N_POSES, seed=seed, **kw)
    t0 = time.perf_counter()
    d = diagnose_tree(case, data)
    dt = time.perf_counter() - t0
    j = d.as_json()
    if j["verdict"] == "none":
        ans = ("none",)
    elif j["verdict"] == "unexplained":
        ans = ("unexplained",)
    else:
        ans = tuple(sorted(c["id"] for c in j["causes"]))
    want = ("none",) if not truth else tuple(sorted(truth))
    placed = all(set(joints.get(c["id"], [])) <= set(c["joints"]) or c["placement"] in ("all", "size", "branch")
                 for c in j["causes"] if c["id"] in joints) if ans == want else False
    return {"name": name, "truth": "+".join(want), "answer": "+".join(ans), "right": ans == want, "placed": placed,
            "wall_s": dt, "prob": j["causes"][0]["probability"], "ambiguous": j["ambiguous"]}


def speed_19_joint() -> tuple[float, float]:
    """(CPU s, wall s) of the 19-joint, 500-pose, 2-marker diagnosis."""
    from femcheck.robot.diagnosis import diagnose_tree
    from femcheck.robot.simulate import humanoid_case, scaled, simulate_positions
    case, _ = humanoid_case(11, head=True, head_marker=False)
    assert case.tree.n_joints == 19 and len(case.tree.marker_names) == 2
    eff = scaled(case, {"joint_torsion_compliance": {"r2": 1.0, "r3": 1.0}}, 1e-3)
    data, _ = simulate_positions(case, 500, effects=eff, sigma_m=2e-4, seed=11)
    c0, t0 = time.process_time(), time.perf_counter()
    diagnose_tree(case, data)
    return time.process_time() - c0, time.perf_counter() - t0


def run() -> dict:
    cpu, wall = speed_19_joint()
    out = {"tree19_500poses_2markers_cpu_s": round(cpu, 2), "tree19_500poses_2markers_wall_s": round(wall, 2),
           "tree19_cpu_budget_s": CPU_BUDGET_S, "tree19_within_budget": bool(cpu <= CPU_BUDGET_S)}
    rows = [run_scenario(sc, seed=i) for i, sc in enumerate(scenarios())]
    groups = {"clean": lambda r: r["truth"] == "none", "limit": lambda r: r["name"].endswith("/limit"),
              "above": lambda r: r["name"].endswith("/above"), "pair": lambda r: "+" in r["truth"] and "unexpl" not in r["truth"],
              "foreign": lambda r: r["truth"] == "unexplained"}
    for g, sel in groups.items():
        rs = [r for r in rows if sel(r)]
        out[f"{g}_n"] = len(rs)
        out[f"{g}_right_rate"] = round(sum(r["right"] for r in rs) / max(len(rs), 1), 3)
    named = [r for r in rows if r["right"] and r["truth"] not in ("none", "unexplained")]
    out["placed_right_rate"] = round(sum(r["placed"] for r in named) / max(len(named), 1), 3)
    out["scenario_wall_s_median"] = round(float(np.median([r["wall_s"] for r in rows])), 2)
    for (t, a), n in sorted(Counter((r["truth"], r["answer"]) for r in rows).items()):
        out[f"confusion.{t} -> {a}_n"] = n
    out["wrong"] = "; ".join(f"{r['name']}: {r['answer']}" for r in rows if not r["right"])
    return out
