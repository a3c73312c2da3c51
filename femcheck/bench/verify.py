"""Bench: the device FE model of the verification at one point (coarse mesh, one process).

Times the link super-element (the biggest FE solve, once per run), one guideway super-element (one per leg
and point), the dense leg/platform/load-protocol algebra of one point (12 load cases, Hertz fixed point
included) and the P0 whole-device direct solve with beam links, used to check the substructuring.
"""
from __future__ import annotations

import time
from pathlib import Path

AREA = "verify"
CASE = Path("cases/haptic_6psu.toml")


def run() -> dict:
    import femcheck
    from femcheck.fe_device.device_model import build_link, guideway_task, point_geometry, point_model, solve_point
    from femcheck.fe_device.mesh_levels import mesh_sizes
    from femcheck.fe_device.substructure import whole_device_solve

    case = femcheck.load_case(CASE)
    sizes = mesh_sizes(case, "coarse")
    legs = point_geometry(case, ["P0"])
    t0 = time.perf_counter()
    link = build_link(case, "solid", sizes.link_m)
    t_link = time.perf_counter() - t0
    t0 = time.perf_counter()
    lgs = [guideway_task(case, s, "solid", sizes.guideway_m) for s in legs.slider[0]]
    t_lg = (time.perf_counter() - t0) / 6
    m = point_model(case, legs, 0, "P0", lgs, link)
    t0 = time.perf_counter()
    r = solve_point(case, m)
    t_pt = time.perf_counter() - t0
    w = whole_device_solve(case, "P0", [50.0, 0, 0, 0, 0, 0], "rigid", guideway_size_m=sizes.guideway_m, link_kind="beam")
    return {"link_superelement_s": round(t_link, 3), "link_dofs": link.dofs,
            "link_assembly_s": round(link.assembly_s, 3), "link_solve_s": round(link.solve_s, 3),
            "guideway_superelement_s": round(t_lg, 3), "guideway_dofs": lgs[0].dofs,
            "point_load_cases_s": round(t_pt, 4), "load_cases_per_s": round(len(r.cases) / t_pt, 1),
            "whole_device_beam_links_s": round(w.seconds, 3), "whole_device_dofs": w.dofs}
