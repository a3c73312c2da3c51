"""Bench ``fe_contact``: the Hertz sphere-on-flat quarter model at three refinements (issue 5 ``make bench``).

For each refinement (coarse / default / fine; P2 tets graded toward the contact) and both loads (15 N,
50 N as two load steps of one solve): DOFs, mesh + assembly + pairing time, factorization time and count,
back-substitution + low-rank-update time, iterations per load step, approach and contact-radius errors
against Hertz, total wall time (s).
"""
from __future__ import annotations

import time

AREA = "fe_contact"


def run() -> dict:
    from femcheck.fe.checks import hertz_sphere as hs

    out: dict = {}
    for level in ("coarse", "default", "fine"):
        t0 = time.perf_counter()
        model = hs.build(level)
        t_build = time.perf_counter() - t0
        res = hs.solve(model)
        ev = hs.evaluate(model, res)
        wall = time.perf_counter() - t0
        tm = res.timings
        out[f"{level}_dofs"] = int(model.basis.N + 1)
        out[f"{level}_mesh_s"] = round(model.mesh_s, 3)
        out[f"{level}_assembly_and_pairing_s"] = round(t_build - model.mesh_s, 3)
        out[f"{level}_factorize_s"] = round(tm["factorize_s"], 3)
        out[f"{level}_factorizations"] = int(tm["factorizations"])
        out[f"{level}_solve_and_lowrank_s"] = round(tm["solve_s"] + tm["lowrank_s"], 3)
        for e, step in zip(ev, res.steps):
            F = int(e["force_N"])
            out[f"{level}_iterations_{F}N"] = int(step.iterations)
            out[f"{level}_approach_error_{F}N_pct"] = round(100 * e["delta_rel_error"], 3)
            out[f"{level}_radius_error_{F}N_pct"] = round(100 * e["a_rel_error"], 3)
        out[f"{level}_wall_s"] = round(wall, 3)
    return out
