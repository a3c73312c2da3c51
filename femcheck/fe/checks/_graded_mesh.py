"""Structured tetrahedral meshes graded toward a contact point or line, for the Hertz verification problems.

:func:`radial_box` maps the cube shells of a uniform n³ tensor grid (integer coordinates ξ, shell index
s = max ξ_i) onto radii ρ_s: x = ρ_s ξ / s. The first shells have the constant width h0 (a uniformly fine
contact zone), the rest grow geometrically to the box size L (:func:`shell_radii`). Every shell keeps
the tensor connectivity, so the mesh is conforming, made of 6 tets per cell, and has no hanging nodes.
Shell s has s cells across each face, so graded shells are stretched radially (radial width / tangential
size 4.4–6.7 in the outermost shell of the former Hertz-sphere levels) and the far field costs most of the cells.
:func:`radial_slab` does the same in the (x, z) plane for plane-strain line contact.

:func:`cored_box` is the "O-grid" alternative used by the Hertz sphere: a uniform n³ core of cubes of side h0,
then layers that are radially scaled copies of the core's outer surface (x = ρ_k η, η on the outer faces of
the unit cube), so every layer keeps the core's 3n² faces. The tangential cell size grows ∝ ρ, the radial
width follows the given radii (:func:`layer_radii`: geometric growth in two bands), and a mesh refined by
scaling n, h0 and the layer counts by one factor is a refinement of a fixed grading (same radii law).
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


def layer_radii(rho_core: float, rho_band: float, L: float, n_band: int, n_far: int) -> np.ndarray:
    """Outer radii (m) of the O-grid layers of :func:`cored_box`: ``n_band`` layers growing geometrically from
    ``rho_core`` to ``rho_band`` (the contact band), then ``n_far`` layers growing geometrically to L."""
    if not 0.0 < rho_core < rho_band < L or n_band < 1 or n_far < 1:
        raise ValueError(f"layer radii: need 0 < {rho_core} < {rho_band} < {L} m and n_band, n_far ≥ 1")
    band = rho_core * (rho_band / rho_core) ** (np.arange(1, n_band + 1) / n_band)
    far = rho_band * (L / rho_band) ** (np.arange(1, n_far + 1) / n_far)
    far[-1] = L
    return np.r_[band, far]


#: prism vertex permutations [a, b, c, a', b', c'] that bring vertex j to position 0 (rotations of the
#: triangle; bottom/top exchange for j ≥ 3)
_PRISM_PERM = np.array([[0, 1, 2, 3, 4, 5], [1, 2, 0, 4, 5, 3], [2, 0, 1, 5, 3, 4],
                        [3, 5, 4, 0, 2, 1], [4, 3, 5, 1, 0, 2], [5, 4, 3, 2, 1, 0]])


def prism_tets(P: np.ndarray) -> np.ndarray:
    """(4, 3k) tets of the k prisms P (6, k) = [a, b, c, a', b', c'] (bottom and top triangles, global
    vertex indices). Every quad face is split along the diagonal through its smallest vertex index
    (Dompierre et al. 1999), so prisms sharing a quad face split it alike and the mesh is conforming."""
    P = np.asarray(P)
    V = np.take_along_axis(P, _PRISM_PERM[np.argmin(P, axis=0)].T, axis=0)
    diag15 = np.minimum(V[1], V[5]) < np.minimum(V[2], V[4])
    split = np.where(diag15[None, None, :], np.array([[0, 1, 2, 5], [0, 1, 5, 4], [0, 4, 5, 3]])[:, :, None],
                     np.array([[0, 1, 2, 4], [0, 4, 2, 5], [0, 4, 5, 3]])[:, :, None])  # (3, 4, k)
    return np.hstack([np.take_along_axis(V, split[i], axis=0) for i in range(3)])


def _positive(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Tets reordered to positive orientation (two vertices swapped where the volume is negative)."""
    a, b, c, d = (p[:, t[i]] for i in range(4))
    neg = np.einsum("ij,ij->j", np.cross(b - a, c - a, axis=0), d - a) < 0
    t = t.copy()
    t[[0, 1]] = np.where(neg, t[[1, 0]], t[[0, 1]])
    return t


def cored_box(h0: float, n: int, radii) -> skfem.MeshTet:
    """Tet mesh of the cube [0, L]³ (L = radii[-1]) graded toward the origin as an O-grid.

    Core: the uniform n³ tensor grid of cubes of side h0 (6 tets each), ρ_core = n h0. Layers: for each
    radius ρ_k in ``radii`` (increasing, > ρ_core), the core's outer surface (its faces x, y or z = ρ_core,
    3n² squares, 6n² triangles) scaled by ρ_k/ρ_core; each triangle swept between two layers is a prism of 3
    tets (:func:`prism_tets`). The symmetry planes x, y, z = 0 stay planes; the last layer is the cube
    surface max(x, y, z) = L. Tangential cell size ρ/n, radial width ρ_k − ρ_(k−1).
    """
    radii = np.asarray(radii, dtype=float)
    rho_c = n * h0
    if radii.size < 1 or radii[0] <= rho_c or np.any(np.diff(radii) <= 0):
        raise ValueError(f"cored_box: layer radii must increase from above the core radius {rho_c} m")
    i = np.arange(n + 1, dtype=float) * h0
    core = skfem.MeshTet.init_tensor(i, i, i)
    p, t = core.p, core.t
    bf = core.boundary_facets()
    outer = np.all(p[:, core.facets[:, bf]].max(axis=0) > rho_c * (1.0 - 1e-9), axis=0)
    tri = core.facets[:, bf[outer]]  # (3, 6n²) triangles of the outer surface
    surf = np.unique(tri)
    local = np.full(p.shape[1], -1)
    local[surf] = np.arange(surf.size)
    eta = p[:, surf] / rho_c  # max-norm 1
    n0 = p.shape[1]
    layer = [surf] + [n0 + k * surf.size + np.arange(surf.size) for k in range(radii.size)]
    tets = [t] + [prism_tets(np.vstack([layer[k][local[tri]], layer[k + 1][local[tri]]]))
                  for k in range(radii.size)]
    P = np.hstack([p] + [r * eta for r in radii])
    return skfem.MeshTet(np.ascontiguousarray(P), np.ascontiguousarray(_positive(P, np.hstack(tets))))
