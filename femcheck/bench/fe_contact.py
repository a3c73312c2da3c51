"""Bench ``fe_contact``: the Hertz sphere-on-flat quarter model at three refinements.

For each refinement (coarse / default / fine = refinement factor k = 3 / 4 / 5 of one O-grid mesh family,
P2 tets graded toward the contact; see :mod:`femcheck.fe.checks.hertz_sphere`) and both loads (15 N, 50 N as
two load steps of one solve): DOFs, core cell size (µm), mesh + assembly + pairing time, factorization time
and count, back-substitution + low-rank-update time, iterations per load step, signed approach and
contact-radius errors against Hertz ((FE − Hertz)/Hertz, %), total wall time (s), and the observed order
of convergence of the approach error between consecutive levels (cell size ∝ 1/k).
Bench target: default (≈ 45k DOFs) solved for both loads with |approach error| ≤ 1 % in ≤ 30 s.
"""
from __future__ import annotations

import math
import time

AREA = "fe_contact"


def run() -> dict:
    from femcheck.fe.checks import hertz_sphere as hs

    out: dict = {"geometry": "half-space"}
    errs: dict = {}
    for level in ("coarse", "default", "fine"):
        t0 = time.perf_counter()
        model = hs.build(level)
        t_build = time.perf_counter() - t0
        res = hs.solve(model)
        ev = hs.evaluate(model, res)
        wall = time.perf_counter() - t0
        tm = res.timings
        k = hs.LEVELS[level]
        out[f"{level}_refinement_k"] = k
        out[f"{level}_core_cell_um"] = round(1e6 * hs.RHO_CORE / k, 3)
        out[f"{level}_dofs"] = int(model.basis.N + 1)
        out[f"{level}_mesh_s"] = round(model.mesh_s, 3)
        out[f"{level}_assembly_and_pairing_s"] = round(t_build - model.mesh_s, 3)
        out[f"{level}_factorize_s"] = round(tm["factorize_s"], 3)
        out[f"{level}_factorizations"] = int(tm["factorizations"])
        out[f"{level}_solve_and_lowrank_s"] = round(tm["solve_s"] + tm["lowrank_s"], 3)
        for e, step in zip(ev, res.steps):
            F = int(e["force_N"])
            errs[(level, F)] = e["delta_error"]
            out[f"{level}_iterations_{F}N"] = int(step.iterations)
            out[f"{level}_approach_error_signed_{F}N_pct"] = round(100 * e["delta_error"], 3)
            out[f"{level}_radius_error_signed_{F}N_pct"] = round(100 * e["a_error"], 3)
            # radius from the pressure moments (see hertz_sphere module doc)
            out[f"{level}_radius_fit_error_signed_{F}N_pct"] = round(100 * e["a_fit_error"], 3)
        out[f"{level}_wall_s"] = round(wall, 3)
    for F in (int(f) for f in hs.LOADS_N):
        for lo, hi in (("coarse", "default"), ("default", "fine")):
            e0, e1 = errs[(lo, F)], errs[(hi, F)]
            order = math.log(abs(e0) / abs(e1)) / math.log(hs.LEVELS[hi] / hs.LEVELS[lo]) if e0 and e1 else float("nan")
            out[f"approach_order_{F}N_{lo}_to_{hi}"] = round(order, 2)
    return out
