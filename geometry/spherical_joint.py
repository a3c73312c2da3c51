"""Spherical joint at B_i: steel ball on a polymer seat, either the paper's idealization or a socket.

Local frame: origin at the ball centre B, z = seat normal (the rail direction e in a leg), ball on top
of the seat, nominal contact point Q = (0, 0, -R) (R = ball radius).

* ``seat = "flat"``: sphere on a plane (seed 000 Sect. 3.2.2, Fig. 12; Hertz point contact, docs/conventions.md
  §5): a disk of radius ``seat_radius_m`` and thickness ``seat_thickness_m`` under the ball, touching it at Q.
* ``seat = "socket"``: a cylinder (outer radius R + c + wall) with a spherical cup of radius Rs = R + c
  (c = ``socket_clearance_m``) and depth ``socket_depth_m``, the ball resting on the cup bottom at Q. The
  Hertz model of this conformal contact has 1/R* = 1/R - 1/Rs (``seat_curvature_1_per_m = -1/Rs``).

Meshing (deterministic: two cold builds with the same parameters give bit-identical meshes):

* ball, ``refinement = "structured"`` (default) or ``"uniform"``: a structured cubed-sphere ball
  (geometry.structured.cubed_ball): an inflated core box plus a shell of prism layers and two 1:2
  refining transition layers, every surface node on the exact sphere, the centre of one cube face at the
  contact point Q. The surface has 4 n cells per cube-face edge, n = max(3, ceil(pi R / (8 s))) with the
  surface edge s = 0.35 size: n = 4 at the default 1 mm (volume error -0.41 %), n = 3 (-0.75 %) from
  1.25 mm up, so that coarse meshes stay cheap for the contact FE. With ``"structured"``
  the tets near Q are then bisected (geometry.subdivision.refine_to_size, conforming longest-edge
  bisection, re-snapping the surface) until each one's mean edge (diagonals included) is at most
  h_c + g max(d - contact_zone_radius_m, 0) (d = distance of its centroid from Q, h_c = size /
  contact_refinement, g = grading).
* ball, ``refinement = "sizing_field"``: the former pipeline, kept for comparison: trimesh icosphere ->
  pytetwild with the sizing field h = min(h, h_c + g |x - Q|), boundary nodes projected onto the sphere.
  fTetWild's optimizer is **not** reproducible: two runs with ``num_threads=1`` and ``OMP_NUM_THREADS=1``
  in fresh processes give different meshes, even different node counts (without the optimizer the output
  repeats, but has degenerate tets). pytetwild has no seed argument, and the library links
  ``std::random_device``. So this path is reproducible only through the disk cache, and it is no longer
  the default; the structured joint also meshes 15 (default size) to 50-70 (fine size) times faster,
  with better dihedral angles in the ball and a finer contact zone (measured by `python -m femcheck.bench geometry`).
* seat: a structured graded mesh (``"structured"``: rings and layers fine at Q), or pytetwild too
  (``"sizing_field"``), or uniform (``"uniform"``); `python -m femcheck.bench geometry` compares them.

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
from geometry.regions import boundary_facets, facet_geometry, point_region, region
from geometry.solid_mesh import snap_to_sphere, tetrahedralize
from geometry.structured import circle, extrude, graded_levels, ring_section
from geometry.subdivision import refine_near

PART = "spherical_joint"


def parameters(case, size: float | None = None, *, link_direction=(0.0, 0.0, 1.0), seat: str | None = None,
               contact_size_m: float | None = None, contact_zone_radius_m: float | None = None,
               grading: float | None = None) -> dict:
    """Mesh parameters (the cache key). ``contact_size_m`` / ``contact_zone_radius_m`` override the case's
    contact edge (size / contact_refinement) and fine-zone radius: the graded joint-FE levels
    (:mod:`femcheck.fe_device.mesh_levels`, element size in the Hertz patch a fixed fraction of a)."""
    sj, so, me = case.spherical_joint, case.solid.spherical_joint, case.solid.mesh
    d = np.asarray(link_direction, float)
    d = d / np.linalg.norm(d)
    return {"ball_radius_m": sj.ball_radius_m, "ball_material": sj.ball_material.name, "seat_material": sj.seat_material.name,
            "analytic_seat_curvature_1_per_m": sj.seat_curvature_1_per_m,
            "seat": seat or so.seat, "seat_radius_m": so.seat_radius_m, "seat_thickness_m": so.seat_thickness_m,
            "socket_clearance_m": so.socket_clearance_m, "socket_wall_m": so.socket_wall_m, "socket_depth_m": so.socket_depth_m,
            "contact_zone_radius_m": float(contact_zone_radius_m or so.contact_zone_radius_m), "link_cap_half_angle_deg": so.link_cap_half_angle_deg,
            "link_direction": [round(float(v), 12) for v in d],
            "size_m": float(size or me.spherical_joint_size_m), "contact_refinement": me.contact_refinement,
            "grading": float(grading or me.grading), "refinement": me.refinement, "tetwild_epsilon_rel": me.tetwild_epsilon_rel,
            **({} if contact_size_m is None else {"contact_size_m": float(contact_size_m)})}


def build(case, size: float | None = None, *, link_direction=(0.0, 0.0, 1.0), seat: str | None = None,
          use_cache: bool = True, contact_size_m: float | None = None, contact_zone_radius_m: float | None = None,
          grading: float | None = None) -> PartMesh:
    """Mesh of ball + seat (see module doc). size: edge length away from the contact, m; link_direction:
    unit vector (local frame) of the link leaving the ball (sets the coupling cap); seat overrides the case;
    contact_size_m / contact_zone_radius_m override the contact edge and fine-zone radius (:func:`parameters`)."""
    p = parameters(case, size, link_direction=link_direction, seat=seat, contact_size_m=contact_size_m,
                   contact_zone_radius_m=contact_zone_radius_m, grading=grading)
    return cached_build(PART, p, lambda: mesh(p), use_cache)


#: ball surface edge about BALL_SURFACE_EDGE_PER_SIZE * size (the interior is coarser, the contact zone finer)
BALL_SURFACE_EDGE_PER_SIZE = 0.35
#: at least 3 core cells (12 surface cells per cube-face edge): ball volume error about -0.75 %; 2 would give -1.7 %
BALL_MIN_CORE_CELLS = 3


def _ball(p, h, h_c, g):
    """(points, tets) of the ball: structured cubed sphere (default) or pytetwild (``sizing_field``)."""
    if p["refinement"] == "sizing_field":
        return _ball_tetwild(p, h, h_c, g, subdivide=False)
    return _ball_structured(p, h, h_c, g, graded=p["refinement"] == "structured")


def _ball_structured(p, h, h_c, g, graded: bool = True):
    """Cubed-sphere ball (geometry.structured.cubed_ball), bisected toward Q when ``graded``. Deterministic."""
    from geometry.solid_mesh import compact
    from geometry.structured import cubed_ball
    from geometry.subdivision import refine_to_size
    R = p["ball_radius_m"]
    q = np.array([0.0, 0.0, -R])
    # the surface has 4 n_core cells of (pi/2) R / (4 n_core) per cube-face edge
    n_core = max(BALL_MIN_CORE_CELLS, math.ceil(math.pi * R / (8.0 * BALL_SURFACE_EDGE_PER_SIZE * h) - 1e-9))
    try:
        pts, tets = cubed_ball(R, n_core)
    except ValueError as exc:
        raise MeshingError(PART, p, str(exc)) from exc
    pts = snap_to_sphere(pts, np.unique(boundary_facets(tets)), [0, 0, 0], R)  # exact up to round-off already
    if graded:
        zone = p["contact_zone_radius_m"]

        def size(x):
            return h_c + g * np.maximum(np.linalg.norm(x - q, axis=1) - zone, 0.0)
        if "contact_size_m" in p:  # graded joint-FE levels: fine on the contact disc only, graded in depth
            size = _disc_size(p, h_c, g)

        def snap(x, nodes):
            return snap_to_sphere(x, nodes, [0, 0, 0], R)
        pts, tets = refine_to_size(pts, tets, size, part=PART, parameters=p, snap=snap)
    return compact(pts, tets)


def _ball_tetwild(p, h, h_c, g, subdivide: bool = False):
    """The former ball: icosphere -> pytetwild with a sizing field, surface snapped onto the sphere, optionally
    bisected near Q (geometry.subdivision.refine_near). NOT reproducible without the cache (fTetWild)."""
    import trimesh
    R = p["ball_radius_m"]
    q = np.array([0.0, 0.0, -R])
    sub = 5 if min(h_c, h) < 0.06 * R else 4  # input facets below the finest element size
    surface = trimesh.creation.icosphere(subdivisions=sub, radius=R)
    sizing = None if p["refinement"] == "uniform" else (lambda x: np.minimum(h, h_c + g * np.linalg.norm(x - q, axis=1)))
    # envelope: the sagitta of a chord h/2 on the sphere; finer is wasted since the surface nodes are snapped
    eps = max(p["tetwild_epsilon_rel"], (h / 2) ** 2 / (8 * R) / (2 * math.sqrt(3) * R))
    pts, tets = tetrahedralize(surface, h, part=PART, parameters=p, sizing=sizing, epsilon_rel=eps)
    pts = snap_to_sphere(pts, np.unique(boundary_facets(tets)), [0, 0, 0], R)
    if subdivide:
        def snap(x, nodes):
            return snap_to_sphere(x, nodes, [0, 0, 0], R)
        pts, tets = refine_near(pts, tets, q, h_c, p["contact_zone_radius_m"], part=PART, parameters=p, snap=snap)
    return pts, tets


def _disc_size(p, h_c, g):
    """Target size (m) of the graded joint-FE levels: h_c on the contact disc (radius contact_zone_radius_m
    about Q in the tangent plane z = -R) and h_c + g d at a distance d from it, so that the elements are
    fine where the Hertz patch and its edge are and grow at once with the depth below it (the bulk keeps
    the structured size)."""
    R, zone = p["ball_radius_m"], p["contact_zone_radius_m"]

    def size(x):
        rho = np.hypot(x[:, 0], x[:, 1])
        return h_c + g * np.hypot(np.maximum(rho - zone, 0.0), x[:, 2] + R)
    return size


def _seat_refined(p, h, h_c, g):
    """Graded joint-FE levels: the uniform structured seat (size h) bisected toward the contact disc
    (:func:`_disc_size`, geometry.subdivision.refine_to_size); a socket's refined cup nodes are snapped
    back onto the cup sphere."""
    from geometry.solid_mesh import compact
    from geometry.subdivision import refine_to_size
    pts, tets, volume = _seat_structured(p, h, h, 0.0)
    snap = None
    if p["seat"] == "socket":
        R, c = p["ball_radius_m"], p["socket_clearance_m"]
        rs, centre = R + c, np.array([0.0, 0.0, c])

        def snap(x, nodes):
            d = np.linalg.norm(x[nodes] - centre, axis=1)
            on_cup = nodes[np.abs(d - rs) < 1e-3 * rs]
            return snap_to_sphere(x, on_cup, centre, rs)
    pts, tets = refine_to_size(pts, tets, _disc_size(p, h_c, g), part=PART, parameters=p, snap=snap)
    pts, tets = compact(pts, tets)
    return pts, tets, volume


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
    h_c = h if uniform else p.get("contact_size_m", h / p["contact_refinement"])
    g = p["grading"]
    _seat_structured(p, h, h, 0.0)  # validates the seat dimensions in milliseconds, before any pytetwild run
    if p["refinement"] == "sizing_field":
        seat_pts, seat_tets, seat_vol = _seat_tetwild(p, h, h_c, g, uniform=False)
    elif uniform:
        seat_pts, seat_tets, seat_vol = _seat_structured(p, h, h, 0.0)
    elif "contact_size_m" in p:
        seat_pts, seat_tets, seat_vol = _seat_refined(p, h, h_c, g)
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
