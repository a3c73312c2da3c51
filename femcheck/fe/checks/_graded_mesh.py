"""Structured tetrahedral meshes graded toward a contact point or line, for the Hertz verification problems.

:func:`radial_box` maps the cube shells of a uniform n³ tensor grid (integer coordinates ξ, shell index
s = max ξ_i) onto radii ρ_s: x = ρ_s ξ / s. The first shells have the constant width h0 (a uniformly fine
contact zone), the rest grow geometrically to the box size L (:func:`shell_radii`). Every shell keeps
the tensor connectivity, so the mesh is conforming, made of 6 tets per cell, and has no hanging nodes.
:func:`radial_slab` does the same in the (x, z) plane for plane-strain line contact.
"""
from __future__ import annotations

import numpy as np
import skfem


def join(lower: skfem.MeshTet, upper: skfem.MeshTet) -> tuple[skfem.MeshTet, int]:
    """Two disjoint bodies in one mesh (coincident vertices are *not* merged); returns (mesh, n_lower_tets)."""
    p = np.hstack([lower.p, upper.p])
    t = np.hstack([lower.t, upper.t + lower.p.shape[1]])
    return skfem.MeshTet(np.ascontiguousarray(p), np.ascontiguousarray(t)), lower.t.shape[1]


def mirror_z(mesh: skfem.MeshTet) -> skfem.MeshTet:
    """Mirror image z → −z (tet orientation restored by swapping two vertices)."""
    return skfem.MeshTet(np.ascontiguousarray(mesh.p * np.array([[1.0], [1.0], [-1.0]])),
                         np.ascontiguousarray(mesh.t[[1, 0, 2, 3]]))


def dof_body(basis, n_lower: int) -> np.ndarray:
    """Body index (0 lower, 1 upper) of every vector DOF of ``basis`` on a :func:`join` mesh."""
    body = np.zeros(basis.N, dtype=np.int8)
    body[basis.element_dofs[:, n_lower:].ravel()] = 1
    return body


def shell_radii(L: float, n: int, h0: float, n_fine: int) -> np.ndarray:
    """Radii ρ_0 = 0 < ρ_1 < … < ρ_n = L (m): n_fine shells of width h0, then geometric growth to L."""
    from scipy.optimize import brentq

    rest = L - n_fine * h0
    m = n - n_fine
    if rest <= 0 or m < 1:
        raise ValueError(f"shell grading: {n_fine} fine shells of {h0} m do not fit in L = {L} m with n = {n}")
    q = brentq(lambda q: h0 * sum(q**j for j in range(1, m + 1)) - rest, 1.0 + 1e-9, 50.0)
    widths = np.r_[np.full(n_fine, h0), h0 * q ** np.arange(1, m + 1)]
    return np.r_[0.0, np.cumsum(widths)]


def radial_box(L: float, n: int, h0: float, n_fine: int) -> skfem.MeshTet:
    """Tet mesh of the cube [0, L]³ graded toward the origin by mapping cube shells onto radii.

    A uniform n³ tensor grid with integer coordinates ξ is mapped by x = ρ_s ξ / s, s = max_i ξ_i (the
    cube shell index) and ρ from :func:`shell_radii`: uniform cells of size h0 for the first ``n_fine``
    shells (the contact zone), geometric growth beyond. n³ cells, 6 tets each; P2 gives ≈ 24 n³ DOFs.
    """
    rho = shell_radii(L, n, h0, n_fine)
    i = np.arange(n + 1, dtype=float)
    m = skfem.MeshTet.init_tensor(i, i, i)
    xi = m.p
    s = np.rint(xi.max(axis=0)).astype(int)
    scale = np.where(s > 0, rho[s] / np.maximum(s, 1), 0.0)
    p = xi * scale[None, :]
    return skfem.MeshTet(np.ascontiguousarray(p), np.ascontiguousarray(m.t))


def radial_slab(L: float, n: int, h0: float, n_fine: int, thickness: float) -> skfem.MeshTet:
    """Plane-strain slab [0, L] × [0, thickness] × [0, L] graded toward the line x = z = 0.

    The (x, z) square shells of an n × 1 × n tensor grid are mapped onto the radii of :func:`shell_radii`
    (as :func:`radial_box` does in 3D); one cell through the thickness (y).
    """
    rho = shell_radii(L, n, h0, n_fine)
    i = np.arange(n + 1, dtype=float)
    m = skfem.MeshTet.init_tensor(i, np.array([0.0, 1.0]), i)
    xi = m.p
    s = np.rint(np.maximum(xi[0], xi[2])).astype(int)
    scale = np.where(s > 0, rho[s] / np.maximum(s, 1), 0.0)
    p = np.vstack([xi[0] * scale, xi[1] * thickness, xi[2] * scale])
    return skfem.MeshTet(np.ascontiguousarray(p), np.ascontiguousarray(m.t))
