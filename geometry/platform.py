"""Moving platform: a round plate carrying the six U joints and the handle (TCP).

Frame P (docs/conventions.md §2): origin at the platform centre, C_i in the plane z = 0 at radius R_p,
angles theta_p,i. The plate (radius R_p + margin, thickness t, mid-plane at z = offset) is rigid in the
analytical model; the FE side may use it to check that assumption. Material: the guideway material
(aluminium in the reference case). Structured mesh: disk rings extruded through the thickness.

Regions: ``pf_mount_i`` (i = 0..5, coupling, reference C_i): bottom-face patches of radius
``mount_radius_m`` under each C_i; ``pf_handle`` (coupling, reference TCP = tcp_offset_m): top patch of
radius ``handle_radius_m``; ``pf_load`` (load point TCP via pf_handle).
Analytic volume pi (R_p + margin)^2 t.
"""
from __future__ import annotations

import math

import numpy as np

from geometry.build import BodyMesh, assemble, cached_build, check_size
from geometry.errors import MeshingError
from geometry.part_mesh import Body, PartMesh
from geometry.regions import facet_geometry, point_region, region
from geometry.structured import circle, extrude, n_around, ring_section

PART = "platform"


def parameters(case, size: float | None = None) -> dict:
    sp = case.solid.platform
    return {"platform_radius_m": case.geometry.platform_radius_m, "platform_points_m": case.platform_points.round(12).tolist(),
            "tcp_offset_m": list(case.geometry.tcp_offset_m), "thickness_m": sp.thickness_m, "margin_m": sp.margin_m,
            "offset_m": sp.offset_m, "mount_radius_m": sp.mount_radius_m, "handle_radius_m": sp.handle_radius_m,
            "material": case.guideway.material.name, "size_m": float(size or case.solid.mesh.platform_size_m)}


def build(case, size: float | None = None, *, use_cache: bool = True) -> PartMesh:
    """Mesh of the platform plate (see module doc). size: target edge length, m."""
    p = parameters(case, size)
    return cached_build(PART, p, lambda: mesh(p), use_cache)


def mesh(p: dict) -> PartMesh:
    R = p["platform_radius_m"] + p["margin_m"]
    t, z0, h = p["thickness_m"], p["offset_m"], p["size_m"]
    check_size(PART, p, h, min(t, p["mount_radius_m"]))
    if h > p["mount_radius_m"]:
        raise MeshingError(PART, p, f"size_m = {h} exceeds mount_radius_m = {p['mount_radius_m']}: mount patches would be empty")
    nr = max(2, math.ceil(R / h))
    radii = np.linspace(0.0, R, nr + 1)
    counts = [1] + [max(6, math.ceil(2 * math.pi * r / h)) for r in radii[1:]]
    counts[-1] = max(counts[-1], n_around(R, h))
    pts2, tris, _ = ring_section(None, circle(R), radii / R, counts)
    nz = max(2, math.ceil(t / h))
    pts, tets = extrude(pts2, tris, np.linspace(0, 1, nz + 1), z0 - t / 2, z0 + t / 2)
    body = Body("platform", p["material"], math.pi * R**2 * t)
    C = np.asarray(p["platform_points_m"])
    tcp = np.asarray(p["tcp_offset_m"])

    def regions(points, fb):
        f = fb["platform"]
        c, n, _ = facet_geometry(points, f)
        bottom, top = n[:, 2] < -0.999, n[:, 2] > 0.999
        out = {}
        for i, ci in enumerate(C):
            near = np.hypot(c[:, 0] - ci[0], c[:, 1] - ci[1]) < p["mount_radius_m"]
            out[f"pf_mount_{i}"] = region(f"pf_mount_{i}", "coupling", points, f, bottom & near, reference_point=ci,
                                          doc=f"mount of U joint {i} (platform-yoke), reference C_{i}")
        handle = top & (np.hypot(c[:, 0], c[:, 1]) < p["handle_radius_m"])
        out["pf_handle"] = region("pf_handle", "coupling", points, f, handle, reference_point=tcp, doc="handle patch, reference TCP")
        out["pf_load"] = point_region("pf_load", points, tcp, nodes=np.unique(f[handle]), doc="TCP load via pf_handle")
        return out

    return assemble(PART, p, [BodyMesh(body, pts, tets)], regions)
