"""Spherical joint at B_i: steel ball on a polymer seat, either the paper's idealization or a socket.

Local frame: origin at the ball centre B, z = seat normal (the rail direction e in a leg), ball on top
of the seat, nominal contact point Q = (0, 0, -R) (R = ball radius).

* ``seat = "flat"``: sphere on a plane (seed 000 Sect. 3.2.2, Fig. 12; Hertz point contact, CONVENTIONS.md
  §5): a disk of radius ``seat_radius_m`` and thickness ``seat_thickness_m`` under the ball, touching it at Q.
* ``seat = "socket"``: a cylinder (outer radius R + c + wall) with a spherical cup of radius Rs = R + c
  (c = ``socket_clearance_m``) and depth ``socket_depth_m``, the ball resting on the cup bottom at Q. The
  Hertz model of this conformal contact has 1/R* = 1/R - 1/Rs (``seat_curvature_1_per_m = -1/Rs``).

Meshing: the ball is not an extrusion, so it goes through the trimesh -> pytetwild pipeline with a sizing
field, h = min(h, h_c + g |x - Q|) (h_c = size / contact_refinement, g = grading), and its boundary
nodes are projected onto the exact sphere; then (``refinement = "structured"``, the default) the tets
near Q are bisected locally (geometry.subdivision) until their edges reach h_c, re-snapping the surface. The seat is a structured graded mesh (``refinement =
"structured"``: rings and layers fine at Q), or goes through pytetwild too (``"sizing_field"``), or is
uniform (``"uniform"``, which also meshes the ball uniformly); docs/geometry.md compares them.

Regions: ``sj_ball_contact`` (master) / ``sj_seat_contact`` (slave), pair ``sj``: facets within
``contact_zone_radius_m`` of the z axis at the contact; ``sj_ball_link`` (coupling, reference B): ball cap
of half angle ``link_cap_half_angle_deg`` about the link direction; ``sj_seat_mount`` (clamp,
reference B): seat bottom, carried by the slider; ``sj_load`` (load point B via sj_ball_link).
Analytic volumes: ball 4 pi R^3 / 3; flat seat pi Rd^2 t; socket pi Ro^2 H - pi d^2 (3 Rs - d) / 3.
"""
from __future__ import annotations

import math

import numpy as np

from geometry.build import BodyMesh, assemble, cached_build, check_size
from geometry.errors import MeshingError
from geometry.part_mesh import Body, PartMesh
from geometry.regions import facet_geometry, point_region, region
from geometry.solid_mesh import snap_to_sphere, tetrahedralize
from geometry.structured import circle, extrude, graded_levels, ring_section
from geometry.subdivision import refine_near

PART = "spherical_joint"


def parameters(case, size: float | None = None, *, link_direction=(0.0, 0.0, 1.0), seat: str | None = None) -> dict:
    sj, so, me = case.spherical_joint, case.solid.spherical_joint, case.solid.mesh
    d = np.asarray(link_direction, float)
    d = d / np.linalg.norm(d)
    return {"ball_radius_m": sj.ball_radius_m, "ball_material": sj.ball_material.name, "seat_material": sj.seat_material.name,
            "analytic_seat_curvature_1_per_m": sj.seat_curvature_1_per_m,
            "seat": seat or so.seat, "seat_radius_m": so.seat_radius_m, "seat_thickness_m": so.seat_thickness_m,
            "socket_clearance_m": so.socket_clearance_m, "socket_wall_m": so.socket_wall_m, "socket_depth_m": so.socket_depth_m,
            "contact_zone_radius_m": so.contact_zone_radius_m, "link_cap_half_angle_deg": so.link_cap_half_angle_deg,
            "link_direction": [round(float(v), 12) for v in d],
            "size_m": float(size or me.spherical_joint_size_m), "contact_refinement": me.contact_refinement,
            "grading": me.grading, "refinement": me.refinement, "tetwild_epsilon_rel": me.tetwild_epsilon_rel}


def build(case, size: float | None = None, *, link_direction=(0.0, 0.0, 1.0), seat: str | None = None,
          use_cache: bool = True) -> PartMesh:
    """Mesh of ball + seat (see module doc). size: edge length away from the contact, m; link_direction:
    unit vector (local frame) of the link leaving the ball (sets the coupling cap); seat overrides the case."""
    p = parameters(case, size, link_direction=link_direction, seat=seat)
    return cached_build(PART, p, lambda: mesh(p), use_cache)


def _ball(p, h, h_c, g):
    import trimesh
    R = p["ball_radius_m"]
    q = np.array([0.0, 0.0, -R])
    sub = 5 if min(h_c, h) < 0.06 * R else 4  # input facets below the finest element size
    surface = trimesh.creation.icosphere(subdivisions=sub, radius=R)
    sizing = None if p["refinement"] == "uniform" else (lambda x: np.minimum(h, h_c + g * np.linalg.norm(x - q, axis=1)))
    # envelope: the sagitta of a chord h/2 on the sphere; finer is wasted since the surface nodes are snapped
    eps = max(p["tetwild_epsilon_rel"], (h / 2) ** 2 / (8 * R) / (2 * math.sqrt(3) * R))
    pts, tets = tetrahedralize(surface, h, part=PART, parameters=p, sizing=sizing, epsilon_rel=eps)
    from geometry.regions import boundary_facets
    pts = snap_to_sphere(pts, np.unique(boundary_facets(tets)), [0, 0, 0], R)
    if p["refinement"] == "structured":
        # fTetWild's sizing field alone stops well above h_c at the contact (docs/geometry.md): bisect locally
        def snap(x, nodes):
            return snap_to_sphere(x, nodes, [0, 0, 0], R)
        pts, tets = refine_near(pts, tets, q, h_c, p["contact_zone_radius_m"], part=PART, parameters=p, snap=snap)
    return pts, tets


def _ring_levels(radii_breaks, r_zone, h, h_c, g):
    """Ring radii from 0 through ``radii_breaks`` (each one a ring), spacing h_c inside r_zone, growing after."""
    r_end = radii_breaks[-1]
    zone = min(r_zone, r_end)
    inner = np.linspace(0.0, zone, max(2, math.ceil(zone / h_c)) + 1)
    outer = [inner]
    start = zone
    for rb in radii_breaks:
        if rb <= start + 1e-12:
            continue
        h0 = min(h, h_c + g * (start - zone))
        h1 = min(h, h_c + g * (rb - zone))
        outer.append(graded_levels(start, rb, h0, h1, h)[1:])
        start = rb
    return np.concatenate(outer)


def _seat_structured(p, h, h_c, g):
    R, zone = p["ball_radius_m"], p["contact_zone_radius_m"]
    if p["seat"] == "flat":
        ro, t = p["seat_radius_m"], p["seat_thickness_m"]
        if ro <= zone:
            raise MeshingError(PART, p, f"seat_radius_m = {ro} must exceed contact_zone_radius_m = {zone}")
        radii = _ring_levels([ro], zone, h, h_c, g)
        z_top, z_bot, rim = (lambda xy: np.full(len(xy), -R)), -R - t, None
        volume = math.pi * ro**2 * t
    else:
        c, wall, depth, floor = p["socket_clearance_m"], p["socket_wall_m"], p["socket_depth_m"], p["seat_thickness_m"]
        rs = R + c
        if depth > rs:
            raise MeshingError(PART, p, f"socket_depth_m = {depth} exceeds the socket radius {rs} (cup deeper than a hemisphere)")
        ztop = -R + depth
        rim = math.sqrt(max(rs**2 - (ztop - c) ** 2, 0.0))
        ro = rs + wall
        if rim <= zone:
            raise MeshingError(PART, p, f"socket rim radius {rim:.6g} m must exceed contact_zone_radius_m = {zone}")
        radii = _ring_levels([rim, ro], zone, h, h_c, g)
        radii[np.argmin(np.abs(radii - rim))] = rim  # the crease is a ring exactly

        def z_top(xy):
            r2 = np.einsum("ij,ij->i", xy, xy)
            return np.where(r2 < rim**2 * (1 - 1e-12), c - np.sqrt(np.maximum(rs**2 - r2, 0.0)), ztop)
        z_bot = -R - floor
        volume = math.pi * ro**2 * (ztop - z_bot) - math.pi * depth**2 * (3 * rs - depth) / 3.0
    counts = [1] + [max(6, math.ceil(2 * math.pi * r / min(h, h_c + g * max(r - zone, 0.0)))) for r in radii[1:]]
    counts[-1] = max(counts[-1], 48)
    t_levels = radii / radii[-1]
    pts2, tris, _ = ring_section(None, circle(radii[-1]), t_levels, counts)
    # layers: fine (h_c) at the contact surface, growing downward
    depth_total = float(np.max(z_top(pts2)) - z_bot)
    zl = graded_levels(0.0, depth_total, h_c, min(h, h_c + g * depth_total), h)
    zeta = 1.0 - (zl / depth_total)[::-1]
    pts, tets = extrude(pts2, tris, zeta, z_bot, z_top)
    return pts, tets, volume


def _seat_tetwild(p, h, h_c, g, uniform: bool):
    import trimesh
    R = p["ball_radius_m"]
    if p["seat"] == "flat":
        ro, t = p["seat_radius_m"], p["seat_thickness_m"]
        surf = trimesh.creation.cylinder(radius=ro, height=t, sections=128)
        surf.apply_translation([0, 0, -R - t / 2])
        volume = math.pi * ro**2 * t
    else:
        from geometry.solid_mesh import difference
        c, wall, depth, floor = p["socket_clearance_m"], p["socket_wall_m"], p["socket_depth_m"], p["seat_thickness_m"]
        rs, ro = R + c, R + c + wall
        H = depth + floor
        cyl = trimesh.creation.cylinder(radius=ro, height=H, sections=128)
        cyl.apply_translation([0, 0, -R - floor + H / 2])
        cup = trimesh.creation.icosphere(subdivisions=5, radius=rs)
        cup.apply_translation([0, 0, c])
        surf = difference(cyl, cup)
        volume = math.pi * ro**2 * H - math.pi * depth**2 * (3 * rs - depth) / 3.0
    q = np.array([0.0, 0.0, -R])
    sizing = None if uniform else (lambda x: np.minimum(h, h_c + g * np.linalg.norm(x - q, axis=1)))
    pts, tets = tetrahedralize(surf, h, part=PART, parameters=p, sizing=sizing, epsilon_rel=p["tetwild_epsilon_rel"])
    return pts, tets, volume


def mesh(p: dict) -> PartMesh:
    R, h = p["ball_radius_m"], p["size_m"]
    check_size(PART, p, h, R)
    if p["seat"] not in ("flat", "socket"):
        raise MeshingError(PART, p, f"seat = {p['seat']!r}; expected 'flat' or 'socket'")
    uniform = p["refinement"] == "uniform"
    h_c = h if uniform else h / p["contact_refinement"]
    g = p["grading"]
    _seat_structured(p, h, h, 0.0)  # validates the seat dimensions in milliseconds, before the slow ball
    if p["refinement"] == "sizing_field":
        seat_pts, seat_tets, seat_vol = _seat_tetwild(p, h, h_c, g, uniform=False)
    elif uniform:
        seat_pts, seat_tets, seat_vol = _seat_structured(p, h, h, 0.0)
    else:
        seat_pts, seat_tets, seat_vol = _seat_structured(p, h, h_c, g)
    ball_pts, ball_tets = _ball(p, h, h_c, g)
    bodies = [BodyMesh(Body("ball", p["ball_material"], 4.0 / 3.0 * math.pi * R**3), ball_pts, ball_tets),
              BodyMesh(Body("seat", p["seat_material"], seat_vol), seat_pts, seat_tets)]
    zone, link = p["contact_zone_radius_m"], np.asarray(p["link_direction"])
    cos_cap = math.cos(math.radians(p["link_cap_half_angle_deg"]))

    def regions(points, fb):
        fbl, fs = fb["ball"], fb["seat"]
        cb, nb, _ = facet_geometry(points, fbl)
        cs, ns, _ = facet_geometry(points, fs)
        rb = np.hypot(cb[:, 0], cb[:, 1])
        rs_ = np.hypot(cs[:, 0], cs[:, 1])
        cap = (cb @ link) / np.linalg.norm(cb, axis=1) > cos_cap
        zb = cs[:, 2].min()
        bottom = (ns[:, 2] < -0.999) & (np.abs(cs[:, 2] - zb) < 1e-6 * R)
        return {
            "sj_ball_contact": region("sj_ball_contact", "contact", points, fbl, (rb < zone) & (cb[:, 2] < 0), pair="sj", side="master",
                                      doc="ball surface at the seat contact (steel, master)"),
            "sj_seat_contact": region("sj_seat_contact", "contact", points, fs, (rs_ < zone) & (ns[:, 2] > 0.5), pair="sj", side="slave",
                                      doc="seat surface at the ball contact (polymer, slave)"),
            "sj_ball_link": region("sj_ball_link", "coupling", points, fbl, cap, reference_point=[0, 0, 0],
                                   doc="ball cap tied to the proximal link, reference B"),
            "sj_seat_mount": region("sj_seat_mount", "clamp", points, fs, bottom, reference_point=[0, 0, 0],
                                    doc="seat bottom carried by the slider, reference B"),
            "sj_load": point_region("sj_load", points, [0, 0, 0], nodes=np.unique(fbl[cap]), doc="load point B via sj_ball_link"),
        }

    return assemble(PART, p, bodies, regions)
