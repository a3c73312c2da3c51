"""Solid links of a parallel device: each link meshed by the parametric builders and condensed.

A ``tube`` link is the round tube of :mod:`geometry.proximal_link` (outer D, inner d; a solid rod when d = 0), a
``bar`` link the rectangular bar of :mod:`geometry.guideway` (``width_m`` along the section x axis, ``depth_m``
along y), both in their local frame: z along the link from its start node (z = 0) to its end node (z = L),
x = the section x axis. P2 tetrahedra (:mod:`femcheck.fe.elasticity`), both end faces tied by rigid couplings
(RBE2) to a 6-DOF node at their centre, everything else condensed out (Guyan reduction, exact in statics
without interior loads, :func:`femcheck.fe_device.parts.condense_solid`):

    K_link = K_bb − K_bi K_ii⁻¹ K_ib      (12 × 12 free-free, rank 6; N/m, N, N m/rad)

This is the solid counterpart of the 12-DOF beam element of :mod:`femcheck.parallel.beam_fe`; unlike the beam it
is not the analytical model's cantilever formula, so analytical vs solid FE checks the link laws (shear, the
end faces, the section). Element size: :data:`MESH_FACTORS` × the largest section dimension / 3 (default level:
3.3 mm for a 10 mm tube), at least 48 nodes around a tube and 2 elements through its wall (the builders'
rules). Links of equal section, material, length and size are condensed once per process (the Delta's and the
6-PSU legs' links repeat; the hexapod's strut halves change length with the pose).
"""
from __future__ import annotations

import functools
import logging

import numpy as np

log = logging.getLogger(__name__)

MESH_FACTORS = {"coarse": 2.0, "default": 1.0, "fine": 0.5}


def link_mesh_size(link, mesh: str = "default") -> float:
    """Target element edge (m) of a solid link at mesh level ``mesh`` (module doc)."""
    if mesh not in MESH_FACTORS:
        raise ValueError(f"mesh = {mesh!r}; expected one of {', '.join(MESH_FACTORS)}")
    dims = [v for v in (link.outer_diameter_m, link.width_m, link.depth_m) if v]
    return MESH_FACTORS[mesh] * max(dims) / 3.0


def link_stiffness(link, length_m: float, mesh: str = "default") -> np.ndarray:
    """(12, 12) condensed stiffness of the solid ``link`` of length ``length_m`` (m) in its local frame (module
    doc): DOFs (u, θ) of the start node (0, 0, 0), then of the end node (0, 0, L)."""
    if link.element not in ("tube", "bar"):
        raise NotImplementedError(f"link {link.name!r} is {link.element}; only tube and bar links are meshed")
    m = link.material
    key = (link.element, link.outer_diameter_m, link.inner_diameter_m, link.width_m, link.depth_m, m.name,
           float(m.E_Pa), float(m.nu), round(float(length_m), 12), link_mesh_size(link, mesh))
    return _condensed(*key).copy()


@functools.lru_cache(maxsize=512)
def _condensed(element, D, d, b, h, material, E, nu, L, size) -> np.ndarray:
    from femcheck.fe_device.parts import condense_solid
    from geometry.build import cached_build
    if element == "tube":
        from geometry import proximal_link as builder
        p = {"outer_diameter_m": float(D), "inner_diameter_m": float(d or 0.0), "length_m": L, "material": material,
             "size_m": size}
        ends = ("prox_end_B", "prox_end_C")
    else:
        from geometry import guideway as builder
        p = {"width_radial_m": float(b), "depth_tangential_m": float(h), "length_m": L, "material": material,
             "size_m": size}
        ends = ("lg_clamp", "lg_slider")
    pm = cached_build(builder.PART, p, lambda: builder.mesh(p))
    se = condense_solid(pm, E, nu, (), {ends[0]: np.zeros(3), ends[1]: np.array([0.0, 0.0, L])},
                        f"{element} link L={L:.4g} m")
    log.info("solid %s link, L = %.4g m: %d DOFs condensed", element, L, se.dofs)
    return se.K
