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
import time

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


#: elements per batch of the vectorized assembly: bounds the element matrices held at once to
#: CHUNK · (3 n_loc)² · 8 B (P2: 2048 · 900 · 8 B ≈ 15 MB, a few times that in temporaries; small batches
#: stay in cache: measured 0.7 s CPU for the 81 k P2 tets of the universal joint vs 1.4 s at 8192)
CHUNK = 2048
#: elements per scatter into the global blocks (one bincount per 3 × 3 component over this many element
#: matrices: 16384 · 100 · 9 · 8 B ≈ 118 MB buffered; fewer passes over the (9, nnzb) sums)
SCATTER_CHUNK = 8 * CHUNK
METHODS = ("vectorized", "skfem")


def assemble_stiffness(basis, E, nu, *, method: str = "vectorized") -> sp.csr_matrix:
    """Elastic stiffness K (basis.N × basis.N, N/m); E (Pa), ν scalars or per-element arrays (n_elements,).

    ``method="vectorized"`` (default): all element matrices in batched numpy products from scikit-fem's
    mapped scalar gradients and quadrature weights (:func:`_element_stiffness`), summed into the 3 × 3
    block sparsity of the mesh in one pass (:func:`_block_pattern`, :func:`_scatter_blocks`); the same
    matrix as the weak form to round-off, several times faster (``python -m femcheck.bench joints``:
    ``*_assembly_speedup``). ``method="skfem"``: ``skfem.asm`` of the weak form :func:`_elasticity_form`
    (the reference; kept for the tests and the bench).
    """
    if method not in METHODS:
        raise ValueError(f"assembly method = {method!r}; expected one of {', '.join(METHODS)}")
    lam, mu = lame(E, nu)
    if method == "skfem":
        K = asm(_elasticity_form, basis, lam=_per_element(basis, lam, "lambda"), mu=_per_element(basis, mu, "mu"))
        return sp.csr_matrix(K)
    t0 = time.perf_counter()
    nel = basis.mesh.t.shape[1]
    lam_e = _per_element(basis, lam, "lambda")[:, 0]
    mu_e = _per_element(basis, mu, "mu")[:, 0]
    nodes, G = _scalar_gradients(basis)
    n = basis.N // 3
    indptr, indices, position = _block_pattern(nodes, n)
    nloc = nodes.shape[0]
    data = np.zeros((9, indices.size))
    buf = np.empty((3, 3, min(SCATTER_CHUNK, nel), nloc, nloc))
    for s0 in range(0, nel, SCATTER_CHUNK):
        s1 = min(s0 + SCATTER_CHUNK, nel)
        for e0 in range(s0, s1, CHUNK):
            sl = slice(e0, min(e0 + CHUNK, s1))
            buf[:, :, e0 - s0: sl.stop - s0] = _element_stiffness(G[:, :, sl], basis.dx[sl], lam_e[sl], mu_e[sl])
        _scatter_blocks(data, position[s0 * nloc * nloc: s1 * nloc * nloc], buf[:, :, : s1 - s0])
    blocks = np.ascontiguousarray(data.T).reshape(-1, 3, 3)
    K = sp.bsr_matrix((blocks, indices, indptr), shape=(3 * n, 3 * n)).tocsr()
    K.eliminate_zeros()  # as skfem's assembly does: no stored zeros
    log.info("stiffness %d x %d (nnz %d) from %d elements assembled (vectorized) in %.2f s",
             K.shape[0], K.shape[1], K.nnz, nel, time.perf_counter() - t0)
    return K


def _scalar_gradients(basis):
    """Global scalar DOF (location) index (n_loc, n_el) and mapped gradients ∂φ_a/∂x_c (3, n_loc, n_el, n_qp),
    1/m, of the scalar element under ``basis`` (vector local DOF 3a + c = function a, component c, the
    scikit-fem ``ElementVector`` order)."""
    if getattr(basis.elem, "dim", None) != 3 or len(basis.basis) % 3:
        raise ValueError("assemble_stiffness needs the 3-component vector basis of vector_basis()")
    nloc = len(basis.basis) // 3
    ed = basis.element_dofs
    if not np.array_equal(ed[1::3], ed[0::3] + 1) or np.any(ed[0::3] % 3):
        raise ValueError("vector basis DOFs are not interleaved (u_x, u_y, u_z) per location")
    nodes = ed[0::3] // 3
    G = np.stack([np.asarray(basis.basis[3 * a][0].grad)[0] for a in range(nloc)], axis=1)
    return nodes, G


def _element_stiffness(G, dx, lam, mu) -> np.ndarray:
    """Element stiffness blocks (3, 3, n_e, n_loc, n_loc), N/m, of isotropic elasticity:

        K[c, d, e, a, b] = Σ_q w_q |J| (λ ∂_c φ_a ∂_d φ_b + μ ∂_d φ_a ∂_c φ_b + μ δ_cd ∇φ_a · ∇φ_b)

    i.e. σ(φ_b e_d) : ε(φ_a e_c) with Hooke's law (Lamé λ, μ per element): the λ/μ split of Bᵀ D B.
    G (3, n_loc, n_e, n_qp) mapped gradients (1/m), dx (n_e, n_qp) quadrature weight × |det J| (m³),
    lam / mu (n_e,) Pa. M_cd = Σ_q w ∂_c φ_a ∂_d φ_b is formed for c ≤ d only (M_dc = M_cdᵀ); the result
    is averaged with its transpose, so K is exactly symmetric."""
    Gt = np.ascontiguousarray(G.transpose(0, 2, 3, 1))  # (c, e, q, a)
    if np.all(dx > 0):  # symmetric split √w ∂φ · √w ∂φ (the stiffness rules of vector_basis)
        Gt = Gt * np.sqrt(dx)[None, :, :, None]
        W = Gt
    else:  # a rule with negative weights: no square roots
        W = Gt * dx[None, :, :, None]
    ne, nloc = Gt.shape[1], Gt.shape[3]
    M = np.empty((3, 3, ne, nloc, nloc))
    for c in range(3):
        for d in range(c, 3):
            M[c, d] = np.matmul(W[c].transpose(0, 2, 1), Gt[d])
            if d != c:
                M[d, c] = M[c, d].transpose(0, 2, 1)
    lap = M[0, 0] + M[1, 1] + M[2, 2]
    K = lam[None, None, :, None, None] * M
    K += mu[None, None, :, None, None] * M.transpose(1, 0, 2, 3, 4)
    for c in range(3):
        K[c, c] += mu[:, None, None] * lap
    K += K.transpose(1, 0, 2, 4, 3).copy()
    K *= 0.5
    return K


def _block_pattern(nodes, n: int):
    """3 × 3 block sparsity of the vector stiffness of the location connectivity ``nodes`` (n_loc, n_el)
    with n locations: BSR ``indptr`` (n + 1,), ``indices`` (nnzb,) and ``position`` (n_el · n_loc², in
    (element, a, b) order) the block of each local pair. One COO→CSR conversion and one sorted search."""
    nloc, ne = nodes.shape
    nt = np.ascontiguousarray(nodes.T).astype(np.int64)
    rows = np.broadcast_to(nt[:, :, None], (ne, nloc, nloc)).ravel()
    cols = np.broadcast_to(nt[:, None, :], (ne, nloc, nloc)).ravel()
    A = sp.csr_matrix((np.ones(rows.size, np.int8), (rows, cols)), shape=(n, n))
    A.sum_duplicates()  # sorted column indices per row
    keys = np.repeat(np.arange(n, dtype=np.int64), np.diff(A.indptr)) * n + A.indices
    position = np.searchsorted(keys, rows * n + cols)
    return A.indptr.astype(np.int64), A.indices.astype(np.int64), position


def _scatter_blocks(data, position, Ke) -> None:
    """data (9, nnzb) += the element blocks Ke (3, 3, n_e, n_loc, n_loc) at ``position`` (n_e · n_loc²,)."""
    nb = data.shape[1]
    for c in range(3):
        for d in range(3):
            data[3 * c + d] += np.bincount(position, weights=Ke[c, d].reshape(-1), minlength=nb)


def assemble_mass(basis, density, *, method: str = "vectorized") -> sp.csr_matrix:
    """Consistent mass M (basis.N × basis.N, kg); density (kg/m³) scalar or per-element (n_elements,).

    Integrated with a quadrature of order 2·p (exact for straight-sided tets), whatever ``basis`` uses.
    ``method="vectorized"``: M[a c, b d] = δ_cd ρ_e Σ_q w_q |J| φ_a φ_b in batches, summed into the block
    pattern of :func:`assemble_stiffness`; ``"skfem"``: ``skfem.asm`` of :func:`_mass_form` (reference).
    """
    if method not in METHODS:
        raise ValueError(f"assembly method = {method!r}; expected one of {', '.join(METHODS)}")
    p = 2 if basis.elem.elem.maxdeg >= 2 else 1
    mb = skfem.Basis(basis.mesh, basis.elem, intorder=2 * p)
    rho = _per_element(mb, density, "density")
    if method == "skfem":
        return sp.csr_matrix(asm(_mass_form, mb, rho=rho))
    nodes, _ = _scalar_gradients(mb)
    nloc, nel = nodes.shape
    phi = np.stack([np.asarray(mb.basis[3 * a][0])[0] for a in range(nloc)], axis=2)  # (e, q, a)
    n = mb.N // 3
    indptr, indices, position = _block_pattern(nodes, n)
    data = np.zeros((9, indices.size))
    for e0 in range(0, nel, SCATTER_CHUNK):
        sl = slice(e0, min(e0 + SCATTER_CHUNK, nel))
        W = phi[sl] * (rho[sl, 0][:, None] * mb.dx[sl])[:, :, None]  # weights may be negative (order-4 rule)
        Me = np.matmul(W.transpose(0, 2, 1), phi[sl])
        Me = 0.5 * (Me + Me.transpose(0, 2, 1))  # exactly symmetric
        m = np.bincount(position[e0 * nloc * nloc: sl.stop * nloc * nloc], weights=Me.reshape(-1),
                        minlength=indices.size)
        for c in range(3):
            data[4 * c] += m
    blocks = np.ascontiguousarray(data.T).reshape(-1, 3, 3)
    M = sp.bsr_matrix((blocks, indices, indptr), shape=(3 * n, 3 * n)).tocsr()
    M.eliminate_zeros()
    return M


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
