"""Linear guideway: the rectangular rail bar of a prismatic leg, clamped at A_i, slider at B_i.

Local frame A_i (docs/conventions.md §2): origin at the clamp A, z along the rail e, x radial (width b),
y tangential (depth h). The bar spans z in [0, L] with L = s_i, the slider position (the analytical
cantilever length, seed 000 eq. 14 / docs/conventions.md §5), taken at a test point by the inverse
kinematics, or given. Structured mesh (exact box; analytic volume b h L).

Regions: ``lg_clamp`` (z = 0, clamp, reference A), ``lg_slider`` (z = L, coupling to the slider /
seat, reference B = (0, 0, L)), ``lg_load`` (load point B).
"""
from __future__ import annotations

import math

import numpy as np

from geometry.build import BodyMesh, assemble, cached_build, check_size, leg_at
from geometry.part_mesh import Body, PartMesh
from geometry.regions import facet_geometry, point_region, region
from geometry.structured import box

PART = "guideway"


def parameters(case, size: float | None = None, *, length_m: float | None = None, point="P0", chain: int = 0) -> dict:
    """Everything the guideway mesh depends on (SI)."""
    g = case.guideway
    if length_m is None:
        length_m = leg_at(case, point, chain)[5]
    return {"width_radial_m": g.width_radial_m, "depth_tangential_m": g.depth_tangential_m, "length_m": float(length_m),
            "material": g.material.name, "size_m": float(size or case.solid.mesh.guideway_size_m)}


def build(case, size: float | None = None, *, length_m: float | None = None, point="P0", chain: int = 0,
          use_cache: bool = True) -> PartMesh:
    """Mesh of the guideway bar (see module doc). size: target edge length, m."""
    p = parameters(case, size, length_m=length_m, point=point, chain=chain)
    return cached_build(PART, p, lambda: mesh(p), use_cache)


def mesh(p: dict) -> PartMesh:
    b, h, L, size = p["width_radial_m"], p["depth_tangential_m"], p["length_m"], p["size_m"]
    check_size(PART, p, size, min(b, h))
    if not L > 0:
        from geometry.errors import MeshingError
        raise MeshingError(PART, p, f"length_m = {L}; expected > 0")
    # at least 2 elements across each side so that bending is represented
    nx, ny, nz = (max(2, math.ceil(v / size)) for v in (b, h, L))
    pts, tets = box(np.linspace(-b / 2, b / 2, nx + 1), np.linspace(-h / 2, h / 2, ny + 1), np.linspace(0.0, L, nz + 1))
    body = Body("guideway", p["material"], b * h * L)

    def regions(points, fb):
        f = fb["guideway"]
        c, n, _ = facet_geometry(points, f)
        tol = 1e-9 * L
        return {
            "lg_clamp": region("lg_clamp", "clamp", points, f, np.abs(c[:, 2]) < tol, reference_point=[0, 0, 0],
                               doc="bar end clamped to the base at A"),
            "lg_slider": region("lg_slider", "coupling", points, f, np.abs(c[:, 2] - L) < tol, reference_point=[0, 0, L],
                                doc="bar end at the slider B (coupled to the seat of the spherical joint)"),
            "lg_load": point_region("lg_load", points, [0, 0, L], nodes=np.unique(f[np.abs(c[:, 2] - L) < tol]),
                                    doc="load point B, applied through lg_slider"),
        }

    return assemble(PART, p, [BodyMesh(body, pts, tets)], regions)
