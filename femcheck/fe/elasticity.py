"""Small-strain isotropic linear elasticity on tetrahedra (scikit-fem), P2 by default, P1 available.

Physics: Hooke's law σ = λ tr(ε) I + 2 μ ε with ε = ½(∇u + ∇uᵀ), Lamé constants
λ = E ν / ((1 + ν)(1 − 2ν)), μ = E / (2 (1 + ν)). Stiffness K_ij = ∫ σ(φ_j) : ε(φ_i) dV (N/m) and
consistent mass M_ij = ∫ ρ φ_j · φ_i dV (kg); the weak forms are the small pure functions below
(scikit-fem ``models/elasticity.py`` style, material constants captured per element).

DOF layout (scikit-fem ``ElementVector``): the three displacement components of one DOF location are
consecutive, DOFs ``3k, 3k+1, 3k+2`` = (u_x, u_y, u_z) at ``basis.doflocs[:, 3k]``; mesh vertices come
first, then (P2) edge midpoints. :func:`dof_triplets` returns that grouping for couplings and loads.

Units: SI throughout — m, Pa, kg/m³, N; displacement vectors are (basis.N,) in m.
"""
from __future__ import annotations

import logging

import numpy as np
import scipy.sparse as sp
import skfem
from skfem import BilinearForm, LinearForm, asm
from skfem.helpers import ddot, dot, sym_grad, trace

log = logging.getLogger(__name__)


def lame(E, nu):
    """Lamé constants (λ, μ) in Pa from Young's modulus E (Pa) and Poisson's ratio ν (scalars or arrays)."""
    E = np.asarray(E, dtype=float)
    nu = np.asarray(nu, dtype=float)
    if np.any(E <= 0) or np.any(nu <= -1.0) or np.any(nu >= 0.5):
        raise ValueError(f"need E > 0 and -1 < nu < 0.5, got E={E}, nu={nu}")
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    mu = E / (2.0 * (1.0 + nu))
    return lam, mu


def vector_basis(mesh: skfem.MeshTet, order: int = 2, intorder: int | None = None) -> skfem.CellBasis:
    """Vector-valued (3 components) Lagrange basis on a tetrahedral mesh; order 1 (P1) or 2 (P2).

    ``intorder`` defaults to 2·(order − 1), which integrates the stiffness of straight-sided tets exactly
    (strains are polynomials of degree order − 1); :func:`assemble_mass` raises it to 2·order for itself.
    """
    elems = {1: skfem.ElementTetP1, 2: skfem.ElementTetP2}
    if order not in elems:
        raise ValueError(f"element order = {order}; expected 1 (P1) or 2 (P2)")
    return skfem.Basis(mesh, skfem.ElementVector(elems[order]()), intorder=intorder or max(1, 2 * (order - 1)))


def _per_element(basis, value, name: str) -> np.ndarray:
    """Scalar or (n_elements,) material value -> (n_elements, n_quadrature_points) for scikit-fem forms."""
    nel = basis.mesh.t.shape[1]
    nqp = basis.X.shape[1]
    v = np.asarray(value, dtype=float)
    if v.ndim == 0:
        v = np.full(nel, float(v))
    if v.shape != (nel,):
        raise ValueError(f"{name} must be a scalar or an array of shape ({nel},) (one per element), got {v.shape}")
    return np.repeat(v[:, None], nqp, axis=1)


@BilinearForm
def _elasticity_form(u, v, w):
    """σ(u) : ε(v) with σ = λ tr ε I + 2 μ ε (λ, μ given per element as w.lam, w.mu)."""
    eu, ev = sym_grad(u), sym_grad(v)
    return w.lam * trace(eu) * trace(ev) + 2.0 * w.mu * ddot(eu, ev)


@BilinearForm
def _mass_form(u, v, w):
    """ρ u · v."""
    return w.rho * dot(u, v)


def assemble_stiffness(basis, E, nu) -> sp.csr_matrix:
    """Elastic stiffness K (basis.N × basis.N, N/m); E (Pa), ν scalars or per-element arrays (n_elements,).

    Assembles the weak form :func:`_elasticity_form` with ``skfem.asm`` using the quadrature of ``basis``.
    """
    lam, mu = lame(E, nu)
    K = asm(_elasticity_form, basis, lam=_per_element(basis, lam, "lambda"), mu=_per_element(basis, mu, "mu"))
    return sp.csr_matrix(K)


def assemble_mass(basis, density) -> sp.csr_matrix:
    """Consistent mass M (basis.N × basis.N, kg); density (kg/m³) scalar or per-element (n_elements,).

    Integrated with a quadrature of order 2·p (exact for straight-sided tets), whatever ``basis`` uses.
    """
    p = 2 if basis.elem.elem.maxdeg >= 2 else 1
    mb = skfem.Basis(basis.mesh, basis.elem, intorder=2 * p)
    return sp.csr_matrix(asm(_mass_form, mb, rho=_per_element(mb, density, "density")))


def strain(basis, u) -> np.ndarray:
    """Small strain ε at the quadrature points, shape (3, 3, n_elements, n_qp), dimensionless."""
    return sym_grad(basis.interpolate(u))


def stress(basis, u, E, nu) -> np.ndarray:
    """Cauchy stress σ = λ tr ε I + 2 μ ε at the quadrature points, (3, 3, n_elements, n_qp), Pa."""
    lam, mu = lame(E, nu)
    lam_q = _per_element(basis, lam, "lambda")
    mu_q = _per_element(basis, mu, "mu")
    eps = np.asarray(strain(basis, u))
    tr = np.einsum("iiep->ep", eps)
    return 2.0 * mu_q * eps + (lam_q * tr)[None, None] * np.eye(3)[:, :, None, None]


def von_mises_from_stress(sig: np.ndarray) -> np.ndarray:
    """σ_vM = sqrt(3/2 s:s), s the deviator; sig (3, 3, ...) Pa -> (...) Pa."""
    tr = np.einsum("ii...->...", sig)
    s = sig - tr[None, None] / 3.0 * np.eye(3).reshape(3, 3, *([1] * (sig.ndim - 2)))
    return np.sqrt(1.5 * np.einsum("ij...,ij...->...", s, s))


def von_mises(basis, u, E, nu, at: str = "elements") -> np.ndarray:
    """Von Mises stress (Pa).

    ``at="elements"``: quadrature-weighted mean over each element, (n_elements,).
    ``at="nodes"``: volume-weighted average of the element means around each mesh vertex, (n_vertices,).
    """
    vm_q = von_mises_from_stress(stress(basis, u, E, nu))
    wq = basis.dx  # (n_elements, n_qp) quadrature weight × |det J|
    vol = wq.sum(axis=1)
    vm_e = (vm_q * wq).sum(axis=1) / vol
    if at == "elements":
        return vm_e
    if at != "nodes":
        raise ValueError(f"at = {at!r}; expected 'elements' or 'nodes'")
    t = basis.mesh.t
    nv = basis.mesh.p.shape[1]
    num = np.bincount(t.ravel(), weights=np.tile(vm_e * vol, t.shape[0]), minlength=nv)
    den = np.bincount(t.ravel(), weights=np.tile(vol, t.shape[0]), minlength=nv)
    return num / np.where(den > 0, den, 1.0)


def dof_triplets(basis, dofs=None):
    """Group vector DOFs by location: returns ``points`` (m, 3) m and ``dofs`` (m, 3) int (x, y, z DOF).

    ``dofs``: any DOF indices (e.g. ``basis.get_dofs(facets).all()``), each location taken once; None = all.
    """
    all_dofs = np.arange(basis.N) if dofs is None else np.unique(np.asarray(dofs, dtype=np.int64))
    first = np.unique(all_dofs - all_dofs % 3)
    trip = first[:, None] + np.arange(3)[None, :]
    pts = basis.doflocs[:, first].T
    return np.ascontiguousarray(pts), trip


def rigid_body_modes(basis) -> np.ndarray:
    """The six rigid-body displacement fields (basis.N, 6): translations x, y, z and rotations about
    x, y, z through the origin (u = θ × x). Near-nullspace for AMG (``linear_solver`` "amg-cg")."""
    pts, trip = dof_triplets(basis)
    B = np.zeros((basis.N, 6))
    x, y, z = pts.T
    for k in range(3):
        B[trip[:, k], k] = 1.0
    # rotation about x: (0, -z, y); about y: (z, 0, -x); about z: (-y, x, 0)
    B[trip[:, 1], 3], B[trip[:, 2], 3] = -z, y
    B[trip[:, 0], 4], B[trip[:, 2], 4] = z, -x
    B[trip[:, 0], 5], B[trip[:, 1], 5] = -y, x
    return B


@LinearForm
def _traction_form(v, w):
    """t · v on a facet basis (t given as w.t, shape (3, n_facets, n_qp))."""
    return dot(w.t, v)


def assemble_traction(facet_basis, traction) -> np.ndarray:
    """Consistent nodal forces (N,) in N of a constant surface traction ``traction`` (3,) Pa on the facets
    of ``facet_basis`` (a ``skfem.FacetBasis`` of the vector element). Σ f = traction · area."""
    t = np.asarray(traction, dtype=float).reshape(3, 1, 1)
    shape = facet_basis.dx.shape
    return asm(_traction_form, facet_basis, t=np.broadcast_to(t, (3, *shape)).copy())


def facet_area_weights(facet_basis) -> np.ndarray:
    """∫ φ_i dA for every scalar DOF location on the facets, returned per vector DOF triplet.

    Returns (basis.N // 3,) m² indexed by ``dof // 3``: the consistent share of surface area of each
    DOF location (for P2 triangles the corners get 0 and the midsides A/3 of each facet) — the natural
    RBE3 weights for a surface, so that a force on the reference node becomes a consistent traction.
    """
    f = assemble_traction(facet_basis, [1.0, 0.0, 0.0])
    return f[0::3].copy()


def surface_area(facet_basis) -> float:
    """Area (m²) of the facets of ``facet_basis``."""
    return float(facet_basis.dx.sum())
