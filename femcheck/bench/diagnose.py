"""Bench area ``diagnose``: speed of a diagnosis with every candidate pair, and the verdict rates on data
inside and outside the fitted family.

Figures:

* ``diagnose_9pt_all_pairs_s``: wall time of one diagnosis of a 9-point, 6-direction dataset (preload
  sweep, 3 trials) with none, every single effect and every pair weighed (analytical detailed model);
* ``foreign_unexplained_rate``: share of out-of-vocabulary datasets (:mod:`femcheck.experiment.foreign`,
  4 effects x ``SEEDS`` seeds, magnitude 0.1) that get the verdict ``unexplained``;
* ``same_model_named_right_rate``: share of in-vocabulary single-effect datasets (every effect, random
  magnitude and place, ``SEEDS`` seeds) whose first named cause is the hidden one;
* ``same_model_unexplained_rate``: share of those that get ``unexplained`` (false alarms);
* ``noise_6um_unexplained_rate``: the same single-effect sets with twice the case's noise;
* ``diagnose_9pt_all_pairs_cpu_s``, ``diagnose_9pt_located_cpu_s``, ``plan_only_cpu_s``: the same in CPU time of
  the process (on the shared machine the wall time depends on the other jobs' load; the CPU time much less);
* ``diagnose_9pt_located_s``, ``located_two_legs_named_right``: the same protocol with the drive 1.8x softer in
  legs 0 and 3: time, and 1 if the one cause named is ``actuation_in_legs`` in legs 0 and 3;
* ``plan_wall_s``: wall time of ``femcheck plan``'s work on the timed dataset above (the diagnosis with every pair,
  then :func:`femcheck.diagnose.plan.plan_measurements`, budget 3, 120 sampled poses); ``plan_only_s`` the plan
  step alone, ``plan_candidates`` the number of candidate measurements it weighs.
"""
from __future__ import annotations

import time

import femcheck

AREA = "diagnose"
SEEDS = 1
DIRS = ("+x", "+y", "+z")


def run() -> dict:
    from femcheck.diagnose import AnalyticalChainModel, diagnose
    from femcheck.diagnose.effects import VOCABULARY, get_effect
    from femcheck.experiment.foreign import FOREIGN, simulate_foreign
    from femcheck.experiment.simulate import simulate
    from femcheck.measured import process

    case = femcheck.load_case("cases/haptic_6psu.toml")
    model = AnalyticalChainModel(case, "detailed", "rigid")
    r = process(simulate(case, [("actuation_compliance", {"scale": 1.8})], seed=1).data, case)
    t0, c0 = time.perf_counter(), time.process_time()
    d = diagnose(model, r, with_baseline=False)
    t_all = time.perf_counter() - t0
    out = {"diagnose_9pt_all_pairs_s": round(t_all, 2), "diagnose_9pt_all_pairs_cpu_s": round(time.process_time() - c0, 2),
           "diagnose_9pt_candidates": len(d.weighing.explanations)}
    # two legs whose drive is 1.8x softer, same protocol: named as actuation in exactly those legs
    rl = process(simulate(case, [("actuation_in_legs", {"leg0": 1.8, "leg3": 1.8})], seed=1).data, case)
    t0, c0 = time.perf_counter(), time.process_time()
    dl = diagnose(model, rl, with_baseline=False)
    out["diagnose_9pt_located_s"] = round(time.perf_counter() - t0, 2)
    out["diagnose_9pt_located_cpu_s"] = round(time.process_time() - c0, 2)
    out["located_two_legs_named_right"] = int([(c.id, c.legs) for c in dl.causes] == [("actuation_in_legs", (0, 3))])
    from femcheck.diagnose.plan import plan_measurements
    t1, c1 = time.perf_counter(), time.process_time()
    p = plan_measurements(model, r, d.weighing, budget=3)
    t_plan = time.perf_counter() - t1
    out["plan_only_cpu_s"] = round(time.process_time() - c1, 2)
    out.update(plan_wall_s=round(t_all + t_plan, 2), plan_only_s=round(t_plan, 2), plan_candidates=p.n_candidates)
    verdicts = []
    for fid in FOREIGN:
        for s in range(SEEDS):
            rr = process(simulate_foreign(case, fid, 0.1, seed=100 + s, directions=DIRS).data, case)
            verdicts.append(diagnose(model, rr, with_baseline=False).verdict)
    out["foreign_unexplained_rate"] = round(sum(v == "unexplained" for v in verdicts) / len(verdicts), 3)
    for label, sigma in (("same_model", None), ("noise_6um", 6e-6)):
        right, unexpl, n = 0, 0, 0
        for eid in VOCABULARY:
            if eid == "none":
                continue
            for s in range(SEEDS):
                m = model if get_effect(eid).applicable(model) else AnalyticalChainModel(case, "simplified", "rigid")
                rr = process(simulate(case, [(eid, {})], seed=200 + s, directions=DIRS, noise_sigma_m=sigma,
                                      level=m.level).data, case)
                d = diagnose(m, rr, with_baseline=False)
                right += d.causes[0].id == eid
                unexpl += d.verdict == "unexplained"
                n += 1
        if label == "same_model":
            out["same_model_named_right_rate"] = round(right / n, 3)
        out[f"{label}_unexplained_rate"] = round(unexpl / n, 3)
    return out
