"""Proximal link: round tube (outer D, inner d) from the ball centre B_i to the U-joint centre C_i.

Local frame B_i (docs/conventions.md §2): origin B, z = u (link axis). The tube spans z in [0, L] with
L = L2 (proximal_link_length_m; a leg assembly passes the length between the joints instead).
Structured mesh: annulus section (nodes exactly on both circles, at least 48 around, 2 layers through
the wall) extruded along z. Analytic volume pi (D^2 - d^2) L / 4 (the polygon section is within
(2 pi / n)^2 / 6 of it).

Regions: ``prox_end_B`` (z = 0, clamp, reference B: the analytical cantilever root, seed 000 eq. 17),
``prox_end_C`` (z = L, coupling, reference C = (0, 0, L)), ``prox_load`` (load point C).
For links modelled as beams see :mod:`geometry.beam_mesh`.
"""
from __future__ import annotations

import math

import numpy as np

from geometry.build import BodyMesh, assemble, cached_build, check_size
from geometry.errors import MeshingError
from geometry.part_mesh import Body, PartMesh
from geometry.regions import facet_geometry, point_region, region
from geometry.structured import circle, extrude, n_around, ring_section

PART = "proximal_link"


def parameters(case, size: float | None = None, *, length_m: float | None = None) -> dict:
    pl = case.proximal_link
    return {"outer_diameter_m": pl.outer_diameter_m, "inner_diameter_m": pl.inner_diameter_m,
            "length_m": float(length_m if length_m is not None else case.geometry.proximal_link_length_m),
            "material": pl.material.name, "size_m": float(size or case.solid.mesh.proximal_link_size_m)}


def build(case, size: float | None = None, *, length_m: float | None = None, use_cache: bool = True) -> PartMesh:
    """Mesh of the link tube (see module doc). size: target edge length along the tube, m."""
    p = parameters(case, size, length_m=length_m)
    return cached_build(PART, p, lambda: mesh(p), use_cache)


def mesh(p: dict) -> PartMesh:
    D, d, L, size = p["outer_diameter_m"], p["inner_diameter_m"], p["length_m"], p["size_m"]
    check_size(PART, p, size, (D - d) / 2 if d > 0 else D)
    if not L > 0:
        raise MeshingError(PART, p, f"length_m = {L}; expected > 0")
    ro, ri = D / 2, d / 2
    n = n_around(ro, size)
    h_around = 2 * math.pi * ro / n
    if ri > 0:
        nr = max(2, math.ceil((ro - ri) / h_around))
        pts2, tris, _ = ring_section(circle(ri), circle(ro), np.linspace(0, 1, nr + 1), [n] * (nr + 1))
        area = math.pi * (ro**2 - ri**2)
    else:
        nr = max(2, math.ceil(ro / h_around))
        t = np.linspace(0, 1, nr + 1)
        counts = [1] + [max(6, math.ceil(n * tj)) for tj in t[1:]]
        pts2, tris, _ = ring_section(None, circle(ro), t, counts)
        area = math.pi * ro**2
    nz = max(2, math.ceil(L / size))
    pts, tets = extrude(pts2, tris, np.linspace(0, 1, nz + 1), 0.0, L)
    body = Body("link", p["material"], area * L)

    def regions(points, fb):
        f = fb["link"]
        c, _, _ = facet_geometry(points, f)
        tol = 1e-9 * L
        at_c = np.abs(c[:, 2] - L) < tol
        return {
            "prox_end_B": region("prox_end_B", "clamp", points, f, np.abs(c[:, 2]) < tol, reference_point=[0, 0, 0],
                                 doc="tube end at the ball B (cantilever root; coupled to the ball)"),
            "prox_end_C": region("prox_end_C", "coupling", points, f, at_c, reference_point=[0, 0, L],
                                 doc="tube end at the U joint C (coupled to the link yoke)"),
            "prox_load": point_region("prox_load", points, [0, 0, L], nodes=np.unique(f[at_c]),
                                      doc="load point C, applied through prox_end_C"),
        }

    return assemble(PART, p, [BodyMesh(body, pts, tets)], regions)
