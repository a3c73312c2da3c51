"""One whole leg (chain i) of the 6-PSU device assembled at a test point P0..P8.

The parts are meshed in their local frames (each cached on its own) and moved rigidly into the world
frame U with the inverse kinematics of femcheck.kinematics.psu6 (docs/conventions.md §2-3):

* guideway: frame A_i (origin A, z = e, x radial), bar from A up to the seat bottom, i.e. length
  s_i - R_ball - seat_thickness (the slider carriage between bar end and seat is rigid: both couple to B);
* spherical joint: origin B (ball centre), z = e, x = x_A; the link cap points along u;
* proximal link: frame B_i (z = u), tube from the ball surface B + R_ball u to the link-yoke mount
  C - (w/2 + H) u (w, H: yoke arm width and length);
* universal joint: frame B_i at C (z = u, x = a1 = unit(z_U x u)).

``parameters["joins"]`` lists the coupling regions that meet (to be tied to one rigid reference node at
the given point): guideway-seat at B, ball-link at B, link-yoke at the yoke mount. The leg's free ends
are ``lg_clamp`` (at A) and ``uj_platform_mount`` (to the platform at C).
"""
from __future__ import annotations

import numpy as np

from geometry import guideway, proximal_link, spherical_joint, universal_joint
from geometry.build import leg_at, point_index
from geometry.cache import cache_key
from geometry.part_mesh import PartMesh, merge

PART = "leg"


def frames(A, u, e):
    """(R_A, R_B): columns = local axes in U of the guideway frame A_i and the link frame B_i."""
    e = np.asarray(e, float)
    x_a = A - (A @ e) * e
    x_a = x_a / np.linalg.norm(x_a)
    R_A = np.stack([x_a, np.cross(e, x_a), e], axis=1)
    x_b = np.array([-u[1], u[0], 0.0])
    x_b = x_b / np.linalg.norm(x_b)
    R_B = np.stack([x_b, np.cross(u, x_b), u], axis=1)
    return R_A, R_B


def build(case, point="P0", chain: int = 0, size: float | None = None, *, use_cache: bool = True) -> PartMesh:
    """Mesh of leg ``chain`` at test point ``point``; ``size`` scales every part's default size by
    size / spherical_joint_size_m when given (one knob for the whole leg)."""
    k = point_index(point)
    A, B, C, u, e, s = leg_at(case, k, chain)
    R_A, R_B = frames(A, u, e)
    me = case.solid.mesh
    scale = 1.0 if size is None else float(size) / me.spherical_joint_size_m
    R_ball = case.spherical_joint.ball_radius_m
    t_seat = case.solid.spherical_joint.seat_thickness_m
    uj_p = universal_joint.parameters(case)
    w = 2.0 * (uj_p["pin_radius_m"] + uj_p["pin_clearance_m"] + uj_p["yoke_wall_m"])
    z_mount = w / 2 + uj_p["yoke_arm_length_m"]
    L_link = case.geometry.proximal_link_length_m - R_ball - z_mount
    L_bar = s - R_ball - t_seat
    parts = [
        (guideway.build(case, me.guideway_size_m * scale, length_m=L_bar, use_cache=use_cache), R_A, A),
        (spherical_joint.build(case, me.spherical_joint_size_m * scale, link_direction=R_A.T @ u, use_cache=use_cache), R_A, B),
        (proximal_link.build(case, me.proximal_link_size_m * scale, length_m=L_link, use_cache=use_cache), R_B, B + R_ball * u),
        (universal_joint.build(case, me.universal_joint_size_m * scale, use_cache=use_cache), R_B, C),
    ]
    moved = [m.transformed(R, t) for m, R, t in parts]
    points, tets, body_of_tet, bodies, regions = merge(PART, moved)
    joins = [
        {"a": "lg_slider", "b": "sj_seat_mount", "point": B.tolist(), "doc": "slider carriage (rigid) at B"},
        {"a": "sj_ball_link", "b": "prox_end_B", "point": B.tolist(), "doc": "link fixed to the ball"},
        {"a": "prox_end_C", "b": "uj_link_mount", "point": (C - z_mount * u).tolist(), "doc": "link fixed to the link yoke"},
    ]
    params = {"point": f"P{k}", "chain": int(chain), "A_m": A.tolist(), "B_m": B.tolist(), "C_m": C.tolist(), "u": u.tolist(),
              "slider_position_m": s, "guideway_bar_length_m": L_bar, "link_tube_length_m": L_link,
              "part_keys": {m.part: m.cache_key for m, _, _ in parts}, "joins": joins}
    q_bodies = {}
    for m, _, _ in parts:
        q_bodies.update(m.quality["bodies"])
    vals = list(q_bodies.values())
    quality = {"bodies": q_bodies, "watertight": all(v["watertight"] for v in vals),
               "n_inverted": sum(v["n_inverted"] for v in vals),
               "max_abs_volume_rel_error": max(abs(v["volume_rel_error"]) for v in vals),
               "min_dihedral_deg": min(v["min_dihedral_deg"] for v in vals),
               "max_aspect_ratio": max(v["max_aspect_ratio"] for v in vals),
               "n_nodes": int(len(points)), "n_tets": int(len(tets))}
    return PartMesh(part=PART, points=points, tets=tets, body_of_tet=body_of_tet, bodies=bodies, regions=regions,
                    parameters=params, quality=quality, cache_key=cache_key(PART, params))
