"""Universal joint at C_i: a steel cross (two pins) in the bores of two aluminium yokes.

Local frame = link frame B_i at C (docs/conventions.md §2): origin C, z = u (link axis, the link comes from
-z), x = a1 = unit(z_P x u) (the pin axis fixed in the platform yoke), y = a2 = u x a1 (fixed in the
link yoke). Pin a1 lies along x in the two platform-yoke arms centred at x = +-L_u/2, pin a2 along y in
the two link-yoke arms at y = +-L_u/2; each arm is l thick (l = contact_length_m), so each pin is
simply supported over the span L_u = pin_span_m (seed 000 eqs. 36-41, K_UB = 48 E I / L_u^3) and
touches each bore over the length l (Hertz line contact, K_UC = pi l E* / 2). Bore radius = pin radius
+ clearance; with ``pin_position = "bottom"`` the cross sits lower by the clearance, so both pins rest
on the bottom of their bores (line contact at the start, as in the Hertz model).

The cross hub is not meshed: the two pins overlap at the centre and are tied rigidly there (coupling
``uj_hub``), the usual FE idealization of a stiff cross block. Only the yoke arms are meshed (the yoke
bases are rigid in the analytical model): their far faces are the mount couplings.

Meshing: structured and graded: pins are disk sections (at least 48 nodes around, rings fine at the
surface) extruded along their axis; arms are a ring section between the bore circle and the arm
outline (fine at the bore) extruded through the thickness l. Nodes lie exactly on pin and bore circles.

Regions: pairs ``uj_a1`` / ``uj_a2`` with ``uj_a*_pin_contact`` (master, pin surface inside the bores) and
``uj_a*_bore_contact`` (slave, bore surfaces); ``uj_hub`` (coupling, reference: cross centre);
``uj_platform_mount`` (clamp, top faces of the platform arms, reference at their centre);
``uj_link_mount`` (coupling, bottom faces of the link arms, reference at their centre); ``uj_load``
(load point C via uj_link_mount). Analytic volumes: pin pi r^2 (L_u + l); arm l (w (w + H) - pi r_b^2).
"""
from __future__ import annotations

import math

import numpy as np

from geometry.build import BodyMesh, assemble, cached_build, check_size
from geometry.errors import MeshingError
from geometry.part_mesh import Body, PartMesh
from geometry.regions import facet_geometry, point_region, region
from geometry.structured import (circle, extrude, graded_levels, levels_with_zones, n_around, orient_positive,
                                 rectangle, ring_section)

PART = "universal_joint"


def parameters(case, size: float | None = None, *, contact_warp: float = 0.0, contact_size_m: float | None = None,
               axial_size_m: float | None = None, hub_levels: bool = False) -> dict:
    """Mesh parameters (the cache key). ``contact_warp`` A in [0, 1): the angles around pins and bores are
    φ + (A/2) sin 2φ of a uniform φ (0 = uniform), so the spacing is 1 − A times the uniform one at the
    top and bottom lines (where a pin bears) and 1 + A at the sides; ``contact_size_m`` overrides the
    radial (through the surface) contact edge size / contact_refinement; ``axial_size_m`` overrides the
    element length along the pins (whole pin) and through the arm thickness (default: ``size``);
    ``hub_levels`` makes the hub ends (±hub_half_length_m along each pin) element levels, so the rigid hub
    tie covers exactly that length at every size (else the facets whose centroid lies within it). The joint-FE levels
    (:func:`femcheck.fe_device.mesh_levels.joint_mesh_sizes`) use both; the defaults keep the mesh."""
    uj, so, me = case.universal_joint, case.solid.universal_joint, case.solid.mesh
    return {"pin_radius_m": uj.pin_radius_m, "contact_length_m": uj.contact_length_m, "pin_span_m": uj.pin_span_m,
            "pin_material": uj.pin_material.name, "bore_material": uj.bore_material.name,
            "pin_clearance_m": so.pin_clearance_m, "pin_position": so.pin_position, "yoke_wall_m": so.yoke_wall_m,
            "yoke_arm_length_m": so.yoke_arm_length_m, "hub_half_length_m": so.hub_half_length_m,
            "size_m": float(size or me.universal_joint_size_m), "contact_refinement": me.contact_refinement,
            "grading": me.grading, "refinement": me.refinement,
            **({} if not contact_warp else {"contact_warp": float(contact_warp)}),
            **({} if contact_size_m is None else {"contact_size_m": float(contact_size_m)}),
            **({} if axial_size_m is None else {"axial_size_m": float(axial_size_m)}),
            **({} if not hub_levels else {"hub_levels": True})}


def build(case, size: float | None = None, *, use_cache: bool = True, contact_warp: float = 0.0,
          contact_size_m: float | None = None, axial_size_m: float | None = None, hub_levels: bool = False) -> PartMesh:
    """Mesh of cross pins and yoke arms (see module doc). size: edge length away from the contacts, m;
    contact_warp, contact_size_m, axial_size_m, hub_levels: :func:`parameters`."""
    p = parameters(case, size, contact_warp=contact_warp, contact_size_m=contact_size_m,
                   axial_size_m=axial_size_m, hub_levels=hub_levels)
    return cached_build(PART, p, lambda: mesh(p), use_cache)


def warped_circle(r: float, A: float):
    """Circle of radius r parametrised by φ -> angle φ + (A/2) sin 2φ: nodes at uniform φ crowd at the
    top and bottom (spacing 1 − A) and spread at the sides (1 + A); A = 0: the plain circle."""
    if not A:
        return circle(r)
    return lambda ph: circle(r)(ph + 0.5 * A * np.sin(2.0 * ph))


def _pin(r, length, h, h_c, g, zones, A=0.0, h_r=None, h_ax=None):
    """Pin along the local extrusion axis t in [-length/2, length/2]: points in (section x, section y, t).
    h_r: the radial size at the surface (default h_c); A: angular warp (:func:`warped_circle`); h_ax: the
    element length along the axis (default h); zones: intervals whose ends are levels."""
    n = n_around(r, h_c)
    h_r = h_c if h_r is None else h_r
    depth = graded_levels(0.0, r, h_r, min(h, h_r + g * r), h)  # from the surface inward
    radii = r - depth[::-1]
    counts = [1] + [max(6, math.ceil(n * rj / r)) for rj in radii[1:]]
    counts[-1] = n
    pts2, tris, _ = ring_section(None, warped_circle(r, A), radii / r, counts)
    h_ax = h if h_ax is None else h_ax
    lv = levels_with_zones(-length / 2, length / 2, zones, h_ax, h_ax, g)
    return extrude(pts2, tris, (lv - lv[0]) / (lv[-1] - lv[0]), -length / 2, length / 2)


def _arm(rb, y0, y1, z0, z1, x0, x1, h, h_c, g, A=0.0, h_r=None, h_ax=None):
    """Arm with a bore (radius rb, centred at the section origin) through the thickness x0..x1; the section
    outline is the rectangle [y0, y1] x [z0, z1] (section coordinates). h_r: radial size at the bore
    (default h_c); A: angular warp of the bore nodes (:func:`warped_circle`), blended out to the outline;
    h_ax: the element length through the thickness (default h, at least 3 layers)."""
    outline, corners = rectangle(y0, y1, z0, z1)
    n = n_around(rb, h_c)
    h_r = h_c if h_r is None else h_r
    far = max(abs(v) for v in (y0, y1, z0, z1))
    near = min(abs(v) for v in (y0, y1, z0, z1))
    # ring blend levels: graded from the bore (h_r) outward, resolving the far side too
    dist = graded_levels(0.0, near - rb, h_r, min(h, h_r + g * (near - rb)), h)
    k_far = max(len(dist) - 1, math.ceil((far - rb) / h))
    t = np.interp(np.linspace(0, len(dist) - 1, k_far + 1), np.arange(len(dist)), dist / (near - rb))
    pts2, tris, _ = ring_section(warped_circle(rb, A), outline, t, [n] * len(t), extra_angles=corners)
    nx = max(3, math.ceil((x1 - x0) / h) if h_ax is None else math.ceil((x1 - x0) / h_ax - 1e-9))
    return extrude(pts2, tris, np.linspace(0, 1, nx + 1), x0, x1)


def mesh(p: dict) -> PartMesh:
    r, l, Lu, c = p["pin_radius_m"], p["contact_length_m"], p["pin_span_m"], p["pin_clearance_m"]
    wall, H, hub, h = p["yoke_wall_m"], p["yoke_arm_length_m"], p["hub_half_length_m"], p["size_m"]
    check_size(PART, p, h, r)
    rb = r + c
    w = 2.0 * (rb + wall)
    if Lu - l <= w:
        raise MeshingError(PART, p, f"pin_span_m - contact_length_m = {Lu - l:.6g} m leaves no room between the arms of "
                                    f"width {w:.6g} m (2 (pin radius + clearance + yoke wall))")
    if hub >= Lu / 2 - l / 2:
        raise MeshingError(PART, p, f"hub_half_length_m = {hub} reaches into the bores (start at {Lu / 2 - l / 2} m)")
    uniform = p["refinement"] == "uniform"
    h_c = h if uniform else h / p["contact_refinement"]
    g = p["grading"]
    delta = c if p["pin_position"] == "bottom" else 0.0
    Lp = Lu + l
    zones = [(-Lu / 2 - l / 2, -Lu / 2 + l / 2), (Lu / 2 - l / 2, Lu / 2 + l / 2)]
    if p.get("hub_levels"):
        zones.append((-hub, hub))
    A, h_r, h_ax = p.get("contact_warp", 0.0), p.get("contact_size_m", h_c), p.get("axial_size_m")
    sp, st = _pin(r, Lp, h, h_c, g, zones, A, h_r, h_ax)
    pin_vol = math.pi * r**2 * Lp
    bodies = []

    def place(name, material, vol, pts_local, tets, perm, shift):
        P = pts_local[:, perm] + np.asarray(shift, float)
        bodies.append(BodyMesh(Body(name, material, vol), P, orient_positive(P, tets)))

    # section coords (s0, s1, t): pin a1 -> (x, y, z) = (t, s0, s1 - delta); pin a2 -> (s0, t, s1 - delta)
    place("pin_a1", p["pin_material"], pin_vol, sp, st, [2, 0, 1], [0, 0, -delta])
    place("pin_a2", p["pin_material"], pin_vol, sp, st, [0, 2, 1], [0, 0, -delta])
    arm_vol = l * (w * (w + H) - math.pi * rb**2)
    for sign, tag in ((-1, "m"), (1, "p")):
        xc = sign * Lu / 2
        ap, at = _arm(rb, -w / 2, w / 2, -w / 2, w / 2 + H, xc - l / 2, xc + l / 2, h, h_c, g, A, h_r, h_ax)
        place(f"yoke_platform_{tag}", p["bore_material"], arm_vol, ap, at, [2, 0, 1], [0, 0, 0])
        ap, at = _arm(rb, -w / 2, w / 2, -w / 2 - H, w / 2, xc - l / 2, xc + l / 2, h, h_c, g, A, h_r, h_ax)
        place(f"yoke_link_{tag}", p["bore_material"], arm_vol, ap, at, [0, 2, 1], [0, 0, 0])
    z_top, z_bot = w / 2 + H, -w / 2 - H

    def regions(points, fb):
        out = {}
        for axis, pin, yokes in ((0, "pin_a1", ("yoke_platform_m", "yoke_platform_p")), (1, "pin_a2", ("yoke_link_m", "yoke_link_p"))):
            f = fb[pin]
            cc, nn, _ = facet_geometry(points, f)
            along = cc[:, axis]
            lateral = np.abs(nn[:, axis]) < 0.5
            in_bore = np.abs(np.abs(along) - Lu / 2) < l / 2
            pair = f"uj_a{axis + 1}"
            out[f"{pair}_pin_contact"] = region(f"{pair}_pin_contact", "contact", points, f, lateral & in_bore, pair=pair, side="master",
                                                doc=f"pin a{axis + 1} surface inside the bores (steel, master)")
            out[f"_{pin}_hub"] = (f, lateral & (np.abs(along) < hub))
            fy = np.vstack([fb[y] for y in yokes])
            cy, ny, _ = facet_geometry(points, fy)
            other = [k for k in range(3) if k != axis]
            rad = np.hypot(cy[:, other[0]], cy[:, other[1]])
            out[f"{pair}_bore_contact"] = region(f"{pair}_bore_contact", "contact", points, fy, (np.abs(ny[:, axis]) < 0.5) & (rad < rb * 1.0001),
                                                 pair=pair, side="slave", doc=f"bore surfaces of the a{axis + 1} yoke (aluminium, slave)")
        (f1, m1), (f2, m2) = out.pop("_pin_a1_hub"), out.pop("_pin_a2_hub")
        out["uj_hub"] = region("uj_hub", "coupling", points, np.vstack([f1, f2]), np.concatenate([m1, m2]), reference_point=[0, 0, -delta],
                               doc="pin surfaces tied rigidly to the cross hub (both pins), reference: cross centre")
        fp = np.vstack([fb["yoke_platform_m"], fb["yoke_platform_p"]])
        cp, np_, _ = facet_geometry(points, fp)
        out["uj_platform_mount"] = region("uj_platform_mount", "clamp", points, fp, (np_[:, 2] > 0.999) & (np.abs(cp[:, 2] - z_top) < 1e-9),
                                          reference_point=[0, 0, z_top], doc="top faces of the platform-yoke arms (to the platform)")
        fl = np.vstack([fb["yoke_link_m"], fb["yoke_link_p"]])
        cl, nl, _ = facet_geometry(points, fl)
        low = (nl[:, 2] < -0.999) & (np.abs(cl[:, 2] - z_bot) < 1e-9)
        out["uj_link_mount"] = region("uj_link_mount", "coupling", points, fl, low, reference_point=[0, 0, z_bot],
                                      doc="bottom faces of the link-yoke arms (to the proximal link)")
        out["uj_load"] = point_region("uj_load", points, [0, 0, 0], nodes=np.unique(fl[low]), doc="load point C via uj_link_mount")
        return out

    return assemble(PART, p, bodies, regions)
