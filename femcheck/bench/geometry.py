"""Bench ``geometry``: meshing time and element counts per part at the default and a fine size, a
comparison of contact-refinement methods on the spherical-joint seat (structured graded mesh vs
fTetWild sizing field vs local subdivision vs uniform), the spherical-joint ball (structured cubed
sphere, the default, vs the former fTetWild + subdivision ball) and a check that two cold builds of the
spherical joint are identical, all measured without the mesh cache."""
from __future__ import annotations

import os
import tempfile
import time

import numpy as np

AREA = "geometry"

#: fine size = FINE_FACTOR x default size
FINE_FACTOR = 0.8


def _contact_edge(points, tets, q, radius):
    """Mean edge length (m) of the tets whose centroid lies within ``radius`` of the contact point q."""
    from geometry.quality import edge_lengths
    near = np.linalg.norm(points[tets].mean(axis=1) - q, axis=1) < radius
    return float(edge_lengths(points, tets[near]).mean()) if near.any() else float("nan")


def _subdivided_seat(sj, p, h, h_c, q):
    """Uniform structured seat, then local bisection near the contact down to h_c (geometry.subdivision)."""
    from geometry.subdivision import refine_near
    pts, tets, vol = sj._seat_structured(p, h, h, 0.0)
    pts, tets = refine_near(pts, tets, q, h_c, p["contact_zone_radius_m"], part="seat", parameters=p)
    return pts, tets, vol


def run() -> dict:
    from femcheck.case import load_case
    from geometry import PARTS, build_part
    from geometry import spherical_joint as sj

    case = load_case("cases/haptic_6psu.toml")
    me = case.solid.mesh
    defaults = {"guideway": me.guideway_size_m, "proximal_link": me.proximal_link_size_m,
                "spherical_joint": me.spherical_joint_size_m, "universal_joint": me.universal_joint_size_m,
                "platform": me.platform_size_m}
    out: dict = {}
    for part in PARTS:
        if part == "leg":
            continue
        for label, size in (("default", defaults[part]), ("fine", FINE_FACTOR * defaults[part])):
            t0 = time.perf_counter()
            m = build_part(case, part, size, use_cache=False)
            out[f"{part}_{label}_size_mm"] = round(size * 1e3, 4)
            out[f"{part}_{label}_mesh_time_s"] = round(time.perf_counter() - t0, 3)
            out[f"{part}_{label}_tets"] = int(len(m.tets))
            out[f"{part}_{label}_nodes"] = int(len(m.points))
            out[f"{part}_{label}_max_volume_error_pct"] = round(100 * m.quality["max_abs_volume_rel_error"], 4)
            out[f"{part}_{label}_min_dihedral_deg"] = round(m.quality["min_dihedral_deg"], 2)
            if part == "spherical_joint":
                b = m.body_index("ball")
                q = np.array([0.0, 0.0, -case.spherical_joint.ball_radius_m])
                out[f"ball_{label}_contact_edge_mm"] = round(_contact_edge(m.points, m.tets[m.body_of_tet == b], q, 0.5e-3) * 1e3, 4)
                qb = m.quality["bodies"]["ball"]
                out[f"ball_{label}_tets"] = qb["n_tets"]
                out[f"ball_{label}_min_dihedral_deg"] = round(qb["min_dihedral_deg"], 2)
                out[f"ball_{label}_volume_error_pct"] = round(100 * qb["volume_rel_error"], 4)
    # leg assembly from cached parts (what a sweep over points pays)
    with tempfile.TemporaryDirectory() as td:
        old = os.environ.get("FEMCHECK_CACHE")
        os.environ["FEMCHECK_CACHE"] = td
        try:
            t0 = time.perf_counter()
            leg = build_part(case, "leg", point="P1")
            out["leg_cold_time_s"] = round(time.perf_counter() - t0, 3)
            t0 = time.perf_counter()
            build_part(case, "leg", point="P1")
            out["leg_cached_time_s"] = round(time.perf_counter() - t0, 3)
            out["leg_tets"] = int(len(leg.tets))
        finally:
            if old is None:
                os.environ.pop("FEMCHECK_CACHE", None)
            else:
                os.environ["FEMCHECK_CACHE"] = old
    # determinism without the cache (issue acceptance): two cold builds, bit-identical arrays
    a = sj.build(case, use_cache=False)
    b = sj.build(case, use_cache=False)
    out["spherical_joint_cold_builds_identical"] = bool(
        np.array_equal(a.points, b.points) and np.array_equal(a.tets, b.tets)
        and all(np.array_equal(a.regions[k].facets, b.regions[k].facets) for k in a.regions))
    # ball: structured cubed sphere (default) vs the former fTetWild sizing field + local subdivision
    p = sj.parameters(case)
    h = p["size_m"]
    h_c = h / p["contact_refinement"]
    q = np.array([0.0, 0.0, -p["ball_radius_m"]])
    for label, fn in (("structured", lambda: sj._ball_structured(p, h, h_c, p["grading"])),
                      ("tetwild_subdivided", lambda: sj._ball_tetwild(p, h, h_c, p["grading"], subdivide=True))):
        t0 = time.perf_counter()
        pts, tets = fn()
        out[f"ball_{label}_time_s"] = round(time.perf_counter() - t0, 3)
        out[f"ball_{label}_tets"] = int(len(tets))
        out[f"ball_{label}_contact_edge_mm"] = round(_contact_edge(pts, tets, q, 0.5e-3) * 1e3, 4)
    # contact refinement on the seat: target contact edge = size / contact_refinement
    out["seat_target_contact_edge_mm"] = round(h_c * 1e3, 4)
    for label, fn in (("structured", lambda: sj._seat_structured(p, h, h_c, p["grading"])),
                      ("sizing_field", lambda: sj._seat_tetwild(p, h, h_c, p["grading"], uniform=False)),
                      ("uniform_structured", lambda: sj._seat_structured(p, h, h, 0.0)),
                      ("subdivision", lambda: _subdivided_seat(sj, p, h, h_c, q))):
        t0 = time.perf_counter()
        pts, tets, _ = fn()
        out[f"seat_{label}_time_s"] = round(time.perf_counter() - t0, 3)
        out[f"seat_{label}_tets"] = int(len(tets))
        out[f"seat_{label}_contact_edge_mm"] = round(_contact_edge(pts, tets, q, 0.5e-3) * 1e3, 4)
    return out
