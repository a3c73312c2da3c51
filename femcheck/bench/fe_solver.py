"""Bench ``fe_solver``: DOFs vs assembly, factorization and solve time of the P2 solid cantilever
(check ``cantilever-solid``) at four refinements (coarse, default, fine of the check and an extra-fine
60×6×6 one) with the automatically chosen direct solver, plus the extra-fine one with pyamg-preconditioned
CG (setup, iterations, time) for comparison. Also the tip-deflection
error vs Timoshenko at each refinement."""
from __future__ import annotations

import time

from femcheck.fe.checks.cantilever_solid import MESHES, reference_deflection, solve_cantilever

AREA = "fe_solver"


def run() -> dict:
    out = {}
    ref = reference_deflection()
    levels = {**MESHES, "xfine": (60, 6)}
    for name, (nx, ny) in levels.items():
        t0 = time.perf_counter()
        uy, ndof, fac, t = solve_cantilever(nx, ny)
        out[f"{name}_dofs"] = int(ndof)
        out[f"{name}_assembly_s"] = round(t["assembly_s"], 4)
        out[f"{name}_factorization_s"] = round(t["factorization_s"], 4)
        out[f"{name}_solve_s"] = round(t["solve_s"], 4)
        out[f"{name}_total_s"] = round(time.perf_counter() - t0, 4)
        out[f"{name}_solver"] = fac.method
        out[f"{name}_tip_rel_error"] = float(abs(uy - ref) / ref)
    uy, ndof, fac, t = solve_cantilever(*levels["xfine"], method="amg-cg")
    out["xfine_amgcg_setup_s"] = round(t["factorization_s"], 4)
    out["xfine_amgcg_solve_s"] = round(t["solve_s"], 4)
    out["xfine_amgcg_iterations"] = int(fac.iterations)
    out["xfine_amgcg_tip_rel_error"] = float(abs(uy - ref) / ref)
    return out
