"""Mesh convergence of the device FE model at one test point.

The FE deflections of every (level, joints, direction) are computed at the mesh levels ``coarse``,
``default``, ``fine`` (:mod:`femcheck.fe_device.mesh_levels`); the change from each level to the finest
one, |δ_h − δ_fine| / |δ_fine|, measures the discretization error left (the default mesh should be within
2 % of the fine one). Rows are in SI; writers convert.
"""
from __future__ import annotations

import logging

log = logging.getLogger(__name__)

CONVERGENCE_LEVELS = ("coarse", "default", "fine")
CONVERGENCE_TOL = 0.02


def mesh_convergence(case, point: str = "P0", levels=("simplified", "detailed"), mesh_levels=CONVERGENCE_LEVELS,
                     jobs: int = 1, progress=None, known: dict | None = None,
                     joint_laws=None) -> tuple[list[dict], list[dict]]:
    """Rows {level, joints, direction, deflection (mm) per mesh level, change vs the finest (%)} and one row
    per mesh (sizes, DOFs, wall time). ``known`` {mesh level: FEVerification} reuses runs that contain ``point``
    (same mesh and model, so the same numbers). ``joint_laws``: the contact-FE joint laws, held fixed over the
    device mesh levels (this study refines the guideway and link meshes; the joints' own mesh convergence is
    ``check-joints --mesh``, docs/verify.md)."""
    from femcheck.verify.fe import run_fe
    known = known or {}
    runs = {}
    for m in mesh_levels:
        k = known.get(m)
        ok = k is not None and point in k.results and all(lv in k.levels for lv in levels)
        runs[m] = k if ok else run_fe(case, (point,), levels, m, jobs, progress=progress, joint_laws=joint_laws)
    finest = runs[mesh_levels[-1]]
    rows = []
    for key, c in finest.results[point].cases.items():
        lvl, j, d = key
        row = {"point": point, "level": lvl, "joints": j, "direction": d}
        for m, r in runs.items():
            row[f"{m}_mm"] = r.results[point].cases[key].deflection_m * 1e3
        for m in mesh_levels[:-1]:
            row[f"{m}_vs_{mesh_levels[-1]}_%"] = 100 * abs(row[f"{m}_mm"] - row[f"{mesh_levels[-1]}_mm"]) / abs(row[f"{mesh_levels[-1]}_mm"])
        rows.append(row)
    dofs = [{"mesh": m, "guideway_m": r.mesh.guideway_m, "link_m": r.mesh.link_m, "link_dofs": r.dofs["link"],
             "guideway_dofs_max": r.dofs["guideway_max"], "wall_s": r.timings_s["wall"]} for m, r in runs.items()]
    return rows, dofs
