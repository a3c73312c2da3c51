"""Linear multipoint constraints by elimination: u = T q + g.

Every constraint is a set of *relations* ``u_d = Σ_j D_dj u_j + b_d`` that make some DOFs d *dependent*;
all other DOFs are *independent* and form the reduced unknowns q (in ascending DOF order). Relations
may refer to DOFs that are themselves dependent (an RBE2 whose reference node is clamped, a clamp on an
RBE3 slave): :func:`combine` resolves the chains by substitution (u_dep = D u + b iterated until it
no longer changes; a cyclic definition is an error). The result is

    u = T q + g,   T (ndof × nfree, csr),  g (ndof,),

and the reduced equations are  Tᵀ K T q = Tᵀ (f − K g)  (principle of virtual work restricted to the
admissible displacements). Reactions at the dependent DOFs are r = K u − f.

Builders:

* :func:`clamp` — prescribed values (0 for a clamp, a settlement/displacement control otherwise).
* :func:`follow` — DOFs that move with one leader DOF, u_i = u_leader + b_i (a face translating rigidly along
  one axis with an extra unknown).
* :func:`rigid_coupling` (RBE2) — slave translations follow a 6-DOF reference node as a rigid body,
  u_i = u_r + θ_r × (x_i − x_r); slave rotations (beam nodes), if given, equal θ_r.
* :func:`distributing_coupling` (RBE3) — the reference node moves as the weighted least-squares rigid
  fit of the slave translations, [u_r; θ_r] = A⁻¹ Σ w_i G_iᵀ u_i with G_i = [I, −[r_i]×], A = Σ w_i G_iᵀ G_i.
  By duality a wrench W on the reference node is distributed as f_i = w_i G_i A⁻¹ W, whose resultant
  Σ G_iᵀ f_i = W exactly: the coupling transmits force and moment without adding stiffness.

Reference nodes (a rigid platform, a coupling point, a beam node) are extra DOFs appended after the
mesh DOFs: :func:`append_reference_nodes` gives node k the DOFs ``n_mesh + 6k + (0..5)`` =
(u_x, u_y, u_z, θ_x, θ_y, θ_z) in m and rad. Matrices/vectors assembled on the mesh alone are zero-padded
to the full size (:func:`pad`; :meth:`Constraints.reduce_matrix` pads automatically).
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np
import scipy.sparse as sp

from femcheck.kinematics.frames import skew

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class Constraints:
    """Resolved constraints u = T q + g on ``ndof`` DOFs.

    ``dependent`` (nd,) sorted DOF indices eliminated; ``free`` (nfree,) the independent DOFs (q = u[free]);
    ``T`` (ndof × nfree) csr; ``g`` (ndof,); ``relations`` = (dependent, D (nd × ndof) csr, b (nd,)) as given,
    kept so that constraint sets can be combined. Build with the functions of this module.
    """

    ndof: int
    dependent: np.ndarray
    free: np.ndarray
    T: sp.csr_matrix
    g: np.ndarray
    relations: tuple

    @property
    def nfree(self) -> int:
        return int(self.free.size)

    def expand(self, q) -> np.ndarray:
        """Full displacement u = T q + g; q (nfree,) or (nfree, k)."""
        q = np.asarray(q, dtype=float)
        return self.T @ q + (self.g if q.ndim == 1 else self.g[:, None])

    def reduce_matrix(self, K) -> sp.csr_matrix:
        """Tᵀ K T (nfree × nfree). K of size n ≤ ndof is zero-padded (reference-node DOFs)."""
        K = pad(K, self.ndof)
        return sp.csr_matrix(self.T.T @ (K @ self.T))

    def reduce_vector(self, f, K=None) -> np.ndarray:
        """Tᵀ (f − K g): reduced load (nfree,); pass K when g ≠ 0 (prescribed displacements)."""
        f = pad(np.asarray(f, dtype=float), self.ndof)
        if K is not None and np.any(self.g):
            f = f - pad(K, self.ndof) @ self.g
        return self.T.T @ f

    def reactions(self, K, u, f) -> np.ndarray:
        """r = K u − f (ndof,): the constraint forces (nonzero only at constrained/coupled DOFs), N or N·m."""
        return pad(K, self.ndof) @ u - pad(np.asarray(f, dtype=float), self.ndof)


def pad(A, ndof: int):
    """Zero-pad a sparse matrix (n × n) or vector (n,) to ndof (reference-node DOFs appended)."""
    n = A.shape[0]
    if n == ndof:
        return A
    if n > ndof:
        raise ValueError(f"array of size {n} is larger than the constrained system ({ndof} DOFs)")
    if sp.issparse(A):
        A = sp.csr_matrix(A)
        return sp.csr_matrix((A.data, A.indices, np.r_[A.indptr, np.full(ndof - n, A.indptr[-1])]),
                             shape=(ndof, ndof))
    out = np.zeros((ndof,) + A.shape[1:])
    out[:n] = A
    return out


def append_reference_nodes(n_mesh_dofs: int, count: int = 1):
    """Reference nodes after the mesh DOFs: returns (ndof_total, ref_dofs (count, 6) int)."""
    ref = n_mesh_dofs + np.arange(6 * count).reshape(count, 6)
    return n_mesh_dofs + 6 * count, ref


def nodal_wrench(ndof: int, node_dofs, wrench) -> np.ndarray:
    """Load vector (ndof,) with a force (3,) N or wrench (6,) [F; M] N, N·m on one node's DOFs (3 or 6)."""
    node_dofs = np.asarray(node_dofs, dtype=np.int64).ravel()
    w = np.asarray(wrench, dtype=float).ravel()
    if w.size != node_dofs.size:
        raise ValueError(f"wrench has {w.size} components for {node_dofs.size} DOFs")
    f = np.zeros(ndof)
    np.add.at(f, node_dofs, w)
    return f


def _from_relations(ndof: int, dependent, D, b) -> Constraints:
    """Resolve u_dep = D u + b (D may reference dependent DOFs) into u = T q + g."""
    dependent = np.asarray(dependent, dtype=np.int64)
    D = sp.csr_matrix(D, shape=(dependent.size, ndof))
    D.eliminate_zeros()
    b = np.asarray(b, dtype=float).reshape(dependent.size)
    if dependent.size and (dependent.min() < 0 or dependent.max() >= ndof):
        raise ValueError(f"constrained DOF out of range 0..{ndof - 1}")
    uniq, counts = np.unique(dependent, return_counts=True)
    if np.any(counts > 1):
        raise ValueError(f"DOFs constrained twice (conflicting constraints): {uniq[counts > 1][:10].tolist()}")
    order = np.argsort(dependent)
    dependent, D, b = dependent[order], D[order], b[order]
    is_dep = np.zeros(ndof, dtype=bool)
    is_dep[dependent] = True
    free = np.flatnonzero(~is_dep)
    col_of = np.full(ndof, -1, dtype=np.int64)
    col_of[free] = np.arange(free.size)
    # X = [D_i | b] in terms of the free DOFs, substituting dependent references until nothing changes
    Dc = D.tocsc()
    D_d = sp.csr_matrix(Dc[:, dependent])
    base = sp.hstack([Dc[:, free], sp.csr_matrix(b[:, None])], format="csr")
    # D_d must be nilpotent (no DOF depends on itself through a chain): after k substitutions,
    # X_k = Σ_{m<k} D_d^m base is exact once the pattern of D_d^k is empty.
    X = base
    Pk = sp.csr_matrix((np.ones(D_d.nnz), D_d.indices, D_d.indptr), shape=D_d.shape)
    P1 = Pk.copy()
    depth = 0
    while Pk.nnz:
        depth += 1
        if depth > dependent.size:
            raise ValueError("cyclic constraint definition: a dependent DOF depends on itself through a chain")
        X = sp.csr_matrix(D_d @ X + base)
        Pk = sp.csr_matrix(Pk @ P1)
        Pk.data[:] = 1.0
    X = sp.csr_matrix(X)
    Xi, g_dep = X[:, :-1].tocoo(), X[:, -1].toarray().ravel()
    rows = np.r_[free, dependent[Xi.row]]
    cols = np.r_[np.arange(free.size), Xi.col]
    vals = np.r_[np.ones(free.size), Xi.data]
    T = sp.csr_matrix((vals, (rows, cols)), shape=(ndof, free.size))
    g = np.zeros(ndof)
    g[dependent] = g_dep
    return Constraints(ndof=ndof, dependent=dependent, free=free, T=T, g=g, relations=(dependent, D, b))


def none(ndof: int) -> Constraints:
    """No constraint (T = I)."""
    return _from_relations(ndof, np.zeros(0, dtype=np.int64), sp.csr_matrix((0, ndof)), np.zeros(0))


def clamp(ndof: int, dofs, values=0.0) -> Constraints:
    """Prescribe u[dofs] = values (m or rad; scalar or per DOF). values = 0 is a clamp."""
    dofs = np.unique(np.asarray(dofs, dtype=np.int64).ravel()) if np.ndim(values) == 0 else \
        np.asarray(dofs, dtype=np.int64).ravel()
    vals = np.broadcast_to(np.asarray(values, dtype=float), dofs.shape).copy()
    return _from_relations(ndof, dofs, sp.csr_matrix((dofs.size, ndof)), vals)


def follow(ndof: int, dofs, leader: int, offsets=0.0) -> Constraints:
    """u[dofs] = u[leader] + offsets: DOFs that translate with one leader DOF (m; scalar or per DOF), e.g. a
    block's far face moving rigidly with an extra approach unknown that carries the applied force."""
    dofs = np.asarray(dofs, dtype=np.int64).ravel()
    D = sp.csr_matrix((np.ones(dofs.size), (np.arange(dofs.size), np.full(dofs.size, leader))), shape=(dofs.size, ndof))
    return _from_relations(ndof, dofs, D, np.broadcast_to(np.asarray(offsets, dtype=float), dofs.shape))


def _offsets(points, ref_point):
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    return pts, pts - np.asarray(ref_point, dtype=float).reshape(1, 3)


def rigid_coupling(ndof: int, ref_dofs, ref_point, points, dofs, rot_dofs=None) -> Constraints:
    """RBE2: slave translations u_i = u_r + θ_r × r_i, r_i = x_i − x_r (small rotations).

    ref_dofs (6,) reference-node DOFs; ref_point (3,) m; points (m, 3) m slave positions; dofs (m, 3)
    slave translation DOFs; rot_dofs (m, 3) optional slave rotation DOFs (beam nodes), set equal to θ_r.
    """
    ref_dofs = np.asarray(ref_dofs, dtype=np.int64).ravel()
    if ref_dofs.size != 6:
        raise ValueError(f"reference node needs 6 DOFs, got {ref_dofs.size}")
    _, r = _offsets(points, ref_point)
    dofs = np.asarray(dofs, dtype=np.int64).reshape(-1, 3)
    if dofs.shape[0] != r.shape[0]:
        raise ValueError(f"{r.shape[0]} slave points but {dofs.shape[0]} DOF triplets")
    m = r.shape[0]
    # row block for slave i: [I, -skew(r_i)] (3 x 6) acting on the reference DOFs
    G = np.zeros((m, 3, 6))
    G[:, :, :3] = np.eye(3)
    G[:, :, 3:] = -skew(r)
    rows = np.repeat(np.arange(3 * m), 6)
    cols = np.tile(ref_dofs, 3 * m)
    D = sp.csr_matrix((G.reshape(-1), (rows, cols)), shape=(3 * m, ndof))
    dep = dofs.reshape(-1)
    b = np.zeros(3 * m)
    if rot_dofs is not None:
        rot_dofs = np.asarray(rot_dofs, dtype=np.int64).reshape(-1, 3)
        Dr = sp.csr_matrix((np.ones(rot_dofs.size), (np.arange(rot_dofs.size), np.tile(ref_dofs[3:], rot_dofs.shape[0]))),
                           shape=(rot_dofs.size, ndof))
        D = sp.vstack([D, Dr], format="csr")
        dep = np.r_[dep, rot_dofs.reshape(-1)]
        b = np.r_[b, np.zeros(rot_dofs.size)]
    return _from_relations(ndof, dep, D, b)


def distributing_coupling(ndof: int, ref_dofs, ref_point, points, dofs, weights=None) -> Constraints:
    """RBE3: reference node = weighted least-squares rigid fit of the slave translations.

    [u_r; θ_r] = A⁻¹ Σ w_i G_iᵀ u_i,  G_i = [I, −[r_i]×] (3 × 6),  A = Σ w_i G_iᵀ G_i.
    weights (m,) ≥ 0 (default 1; for a surface use :func:`femcheck.fe.elasticity.facet_area_weights`).
    The slaves must not be collinear (A singular otherwise).
    """
    ref_dofs = np.asarray(ref_dofs, dtype=np.int64).ravel()
    if ref_dofs.size != 6:
        raise ValueError(f"reference node needs 6 DOFs, got {ref_dofs.size}")
    _, r = _offsets(points, ref_point)
    dofs = np.asarray(dofs, dtype=np.int64).reshape(-1, 3)
    m = r.shape[0]
    w = np.ones(m) if weights is None else np.asarray(weights, dtype=float).ravel()
    if w.shape != (m,) or np.any(w < 0):
        raise ValueError(f"weights must be ({m},) and >= 0")
    keep = w > 0
    r, dofs, w = r[keep], dofs[keep], w[keep]
    G = np.zeros((r.shape[0], 3, 6))
    G[:, :, :3] = np.eye(3)
    G[:, :, 3:] = -skew(r)
    A = np.einsum("i,iaj,iak->jk", w, G, G)
    # scale rotations by a length so that the 6x6 solve is well conditioned
    L = max(np.sqrt(np.einsum("i,ij,ij->", w, r, r) / w.sum()), 1e-30)
    S = np.diag([1, 1, 1, L, L, L])
    As = S @ A @ S
    if np.linalg.cond(As) > 1e12:
        raise ValueError("distributing coupling: slave points are collinear or too few (singular rigid fit)")
    P = S @ np.linalg.solve(As, S)  # A^-1
    C = np.einsum("jk,i,iak->jia", P, w, G)  # (6, m, 3): d[u_r,θ]/d u_i
    rows = np.repeat(np.arange(6), C.shape[1] * 3)
    cols = np.tile(dofs.reshape(-1), 6)
    D = sp.csr_matrix((C.reshape(-1), (rows, cols)), shape=(6, ndof))
    return _from_relations(ndof, ref_dofs, D, np.zeros(6))


def combine(*constraints: Constraints) -> Constraints:
    """One constraint set from several on the same DOFs; a DOF may be made dependent only once."""
    if not constraints:
        raise ValueError("combine() needs at least one Constraints")
    ndof = constraints[0].ndof
    if any(c.ndof != ndof for c in constraints):
        raise ValueError(f"constraints on different DOF counts: {[c.ndof for c in constraints]}")
    dep = np.concatenate([c.relations[0] for c in constraints])
    D = sp.vstack([c.relations[1] for c in constraints], format="csr")
    b = np.concatenate([c.relations[2] for c in constraints])
    return _from_relations(ndof, dep, D, b)
