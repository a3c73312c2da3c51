"""Line meshes with section properties, for links modelled as beams (guideway bar, link tube).

Section properties follow docs/conventions.md §5 (local z = element axis; Iy = int x^2 dA resists bending
along x): rectangle b x h: A = b h, Iy = h b^3 / 12, Ix = b h^3 / 12, Jt = a c^3 [1/3 - 0.21 (c/a)
(1 - c^4 / (12 a^4))] (a = max, c = min; Roark); tube D/d: A = pi (D^2 - d^2) / 4,
Ix = Iy = pi (D^4 - d^4) / 64, Jt = 2 Ix. Shear coefficients kappa: 5/6 (rectangle), 0.5 (thin tube).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Section:
    """Beam section: A (m^2), Ix, Iy (m^4, about local x and y), Jt (m^4, torsion), kappa (shear, -)."""

    A_m2: float
    Ix_m4: float
    Iy_m4: float
    Jt_m4: float
    kappa: float
    shape: str


def rectangle_section(b: float, h: float) -> Section:
    """b along local x, h along local y (m)."""
    a, c = max(b, h), min(b, h)
    jt = a * c**3 * (1.0 / 3.0 - 0.21 * (c / a) * (1.0 - c**4 / (12.0 * a**4)))
    return Section(b * h, b * h**3 / 12.0, h * b**3 / 12.0, jt, 5.0 / 6.0, "rectangle")


def tube_section(D: float, d: float) -> Section:
    """Outer diameter D, inner d (m); d = 0 gives a solid round bar (kappa 0.9 then)."""
    I = math.pi * (D**4 - d**4) / 64.0
    return Section(math.pi * (D**2 - d**2) / 4.0, I, I, 2.0 * I, 0.5 if d > 0 else 0.9, "tube" if d > 0 else "round")


@dataclass(frozen=True)
class BeamMesh:
    """Straight beam from ``start`` to ``end`` (m): nodes (n, 3), elements (n-1, 2), the section, the
    local frame R (3, 3; columns x, y, z in U, z = axis) and the material name."""

    nodes: np.ndarray
    elements: np.ndarray
    section: Section
    R: np.ndarray
    material: str

    @property
    def length_m(self) -> float:
        return float(np.linalg.norm(self.nodes[-1] - self.nodes[0]))


def beam(start, end, section: Section, material: str, n_elements: int, x_axis=None) -> BeamMesh:
    """Line mesh of ``n_elements`` equal elements; ``x_axis`` (3,) fixes the section's local x (projected
    normal to the axis); default: the docs/conventions.md §2 link frame x = (-u_y, u_x, 0)."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    if n_elements < 1:
        raise ValueError(f"n_elements: got {n_elements}; expected >= 1")
    z = end - start
    L = np.linalg.norm(z)
    if L <= 0:
        raise ValueError("beam: start and end coincide")
    z = z / L
    x = np.array([-z[1], z[0], 0.0]) if x_axis is None else np.asarray(x_axis, float)
    x = x - (x @ z) * z
    if np.linalg.norm(x) < 1e-12:
        x = np.array([1.0, 0.0, 0.0]) - z[0] * z
    x = x / np.linalg.norm(x)
    R = np.stack([x, np.cross(z, x), z], axis=1)
    t = np.linspace(0.0, 1.0, n_elements + 1)
    nodes = start + t[:, None] * (end - start)
    el = np.stack([np.arange(n_elements), np.arange(1, n_elements + 1)], 1)
    return BeamMesh(nodes, el, section, R, material)


def guideway_beam(case, length_m: float, n_elements: int = 20, A=None, e=None) -> BeamMesh:
    """Guideway cantilever as a beam from A along e (frame A_i: x radial)."""
    g = case.guideway
    A = np.zeros(3) if A is None else np.asarray(A, float)
    e = np.asarray(case.geometry.guideway_direction if e is None else e, float)
    radial = A - (A @ e) * e
    x_axis = radial if np.linalg.norm(radial) > 1e-12 else None
    return beam(A, A + length_m * e, rectangle_section(g.width_radial_m, g.depth_tangential_m), g.material.name, n_elements, x_axis)


def link_beam(case, B, C, n_elements: int = 20) -> BeamMesh:
    """Proximal link as a tube beam from B to C (frame B_i)."""
    pl = case.proximal_link
    return beam(B, C, tube_section(pl.outer_diameter_m, pl.inner_diameter_m), pl.material.name, n_elements)
