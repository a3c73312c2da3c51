"""Contact pairing: closest-point projection of slave integration points onto master facets.

Gauss-point-to-surface (GPTS) contact. The slave surface is sampled at the quadrature
points of its facets (triangle rule of order ``intorder``); each slave point x_s is projected once, in the
reference configuration, onto the closest master facet (small sliding: the pairing is not updated).
For slave point i with master point x_m, master outward unit normal n and tangents t1, t2 (n, t1, t2
right-handed orthonormal, the local frame {n, t, τ} of seed 004 §3.2, Fig. 5):

    gap      g_i   = g0_i + n · (u_s − u_m) = g0_i + (B_n u)_i,     g0_i = n · (x_s − x_m) + clearance
    slip     s_i   = [t1; t2] · (u_s − u_m) = (B_t u)_i             (2 components, m)

with u_s = Σ_j N_j(ξ_s) u_j over the shape functions of the slave facet's parent tetrahedron and u_m
likewise on the master side (so the operators are exact for P1 and P2 elements on straight-sided
tetrahedra). g > 0 is open, g < 0 penetration (seed 004 eq. 17: Δu_n = u_Jn − u_In + δ_n).

Pressure is carried by the integration points with their area weights w_i (m²), so a uniform pressure
yields the consistent nodal forces of the slave facets. This passes the patch test exactly (to round-off)
when every slave facet lies inside one master facet (conforming or nested meshes); on general
non-matching meshes the error is the quadrature error of the master shape functions across master
facet edges. Nodal node-to-surface with P2 would give the wrong (corner-node) pressures, see the docs.

Shapes: ``points`` (m, 3) m; ``B_n`` (m, ndof) csr, 1; ``B_t`` (2m, ndof) csr rows [t1 of point 0,
t2 of point 0, t1 of point 1, ...]; ``weights`` (m,) m²; ``g0`` (m,) m.
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree
from skfem.assembly import Dofs
from skfem.quadrature import get_quadrature
from skfem.refdom import RefTri

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class ContactPair:
    """One slave/master surface pair, paired once in the reference configuration (immutable).

    points (m, 3) m: slave integration points; weights (m,) m²: their area weights; g0 (m,) m initial
    gap (clearance included); normal (m, 3), t1 (m, 3), t2 (m, 3): master frame at the projection;
    B_n (m, ndof), B_t (2m, ndof) csr; penalty_n, penalty_t (m,) Pa/m; friction μ (Coulomb, ≥ 0);
    slave_facet (m,) facet index of each point, master_facet (m,) facet it projects on; name.
    """

    name: str
    points: np.ndarray
    weights: np.ndarray
    g0: np.ndarray
    normal: np.ndarray
    t1: np.ndarray
    t2: np.ndarray
    B_n: sp.csr_matrix
    B_t: sp.csr_matrix
    penalty_n: np.ndarray
    penalty_t: np.ndarray
    friction: float
    slave_facet: np.ndarray
    master_facet: np.ndarray
    projection_distance: np.ndarray

    @property
    def n_points(self) -> int:
        return int(self.weights.size)

    def with_penalty(self, factor: float) -> "ContactPair":
        """The same pair with both penalties multiplied by ``factor`` (penalty-independence studies)."""
        return dataclasses.replace(self, penalty_n=self.penalty_n * factor, penalty_t=self.penalty_t * factor)


def _facet_frame(p, facets):
    """Vertices (3, 3, nf) [corner, xyz, facet] and unit normals (nf, 3) of linear triangles."""
    X = p[:, facets]  # (3 xyz, 3 corners, nf)
    e1 = X[:, 1] - X[:, 0]
    e2 = X[:, 2] - X[:, 0]
    n = np.cross(e1.T, e2.T)
    area2 = np.linalg.norm(n, axis=1)
    return X, n / area2[:, None], 0.5 * area2


def _outward(mesh, facets, normals):
    """Flip ``normals`` (nf, 3) so that they point out of the parent tetrahedron of each facet."""
    parent = mesh.f2t[0, facets]
    centroid = mesh.p[:, mesh.t[:, parent]].mean(axis=1).T
    fc = mesh.p[:, mesh.facets[:, facets]].mean(axis=1).T
    s = np.sign(np.einsum("ij,ij->i", fc - centroid, normals))
    return normals * s[:, None], parent


def _closest_on_triangles(x, A, B, C):
    """Closest points on triangles (A, B, C) to x; all (k, 3). Returns (points (k, 3), dist (k,)).

    Vectorized form of the region test of Ericson, Real-Time Collision Detection §5.1.5.
    """
    ab, ac, ap = B - A, C - A, x - A
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = x - B
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = x - C
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    denom = va + vb + vc
    denom = np.where(denom == 0.0, 1e-300, denom)
    v = vb / denom
    w = vc / denom
    out = A + ab * v[:, None] + ac * w[:, None]  # interior
    with np.errstate(divide="ignore", invalid="ignore"):
        # edge regions
        m_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        t = np.where(m_ab, d1 / np.where(d1 - d3 == 0, 1, d1 - d3), 0)
        out = np.where(m_ab[:, None], A + ab * t[:, None], out)
        m_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        t = np.where(m_ac, d2 / np.where(d2 - d6 == 0, 1, d2 - d6), 0)
        out = np.where(m_ac[:, None], A + ac * t[:, None], out)
        m_bc = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
        den = (d4 - d3) + (d5 - d6)
        t = np.where(m_bc, (d4 - d3) / np.where(den == 0, 1, den), 0)
        out = np.where(m_bc[:, None], B + (C - B) * t[:, None], out)
    # vertex regions
    out = np.where(((d1 <= 0) & (d2 <= 0))[:, None], A, out)
    out = np.where(((d3 >= 0) & (d4 <= d3))[:, None], B, out)
    out = np.where(((d6 >= 0) & (d5 <= d6))[:, None], C, out)
    return out, np.linalg.norm(x - out, axis=1)


def _shape_operator(mesh, scalar_elem, element_dofs, tets, x, ndof, coeff):
    """Sparse (m·k, ndof) rows Σ_j N_j(x_i) coeff[i, r, c] at vector DOF 3·dof_j + c.

    tets (m,) parent tetrahedra; x (m, 3) points inside them (m); coeff (m, k, 3) row coefficients
    (e.g. the normal for B_n). Local coordinates from the affine map x = p0 + J ξ.
    """
    P = mesh.p[:, mesh.t[:, tets]]  # (3, 4, m)
    J = np.stack([P[:, 1] - P[:, 0], P[:, 2] - P[:, 0], P[:, 3] - P[:, 0]], axis=-1)  # (3, m, 3)
    J = np.transpose(J, (1, 0, 2))  # (m, 3, 3)
    xi = np.linalg.solve(J, (x - P[:, 0].T)[:, :, None])[:, :, 0].T  # (3, m)
    nb = element_dofs.shape[0]
    N = np.stack([scalar_elem.lbasis(xi, j)[0] for j in range(nb)])  # (nb, m)
    m, k = coeff.shape[0], coeff.shape[1]
    dofs = element_dofs[:, tets]  # (nb, m)
    rows = np.broadcast_to(np.arange(m * k).reshape(1, m, k, 1), (nb, m, k, 3))
    cols = np.broadcast_to((3 * dofs)[:, :, None, None] + np.arange(3)[None, None, None, :], (nb, m, k, 3))
    vals = N[:, :, None, None] * coeff[None, :, :, :]
    return sp.csr_matrix((vals.ravel(), (rows.ravel(), cols.ravel())), shape=(m * k, ndof))


def pair_surfaces(basis, slave_facets, master_facets, *, penalty_n, penalty_t=None, friction: float = 0.0,
                  clearance: float = 0.0, intorder: int = 4, search_k: int = 12, name: str = "pair",
                  ndof: int | None = None) -> ContactPair:
    """Pair the slave facets with the master facets of ``basis`` (vector P1/P2 basis on a MeshTet).

    penalty_n, penalty_t: Pa/m, scalar or (n_slave_facets,) (use :func:`default_penalty`); penalty_t
    defaults to penalty_n. friction: Coulomb μ. clearance: m, added to every initial gap (a radial
    clearance of a joint > 0; an interference fit < 0). intorder: triangle quadrature order on the slave
    facets (4 = 6 points, enough for the patch test with P2). search_k: master facet candidates per point
    (nearest centroids). ndof: total DOFs of the system (≥ basis.N when reference nodes are appended).
    """
    mesh = basis.mesh
    slave_facets = np.asarray(slave_facets, dtype=np.int64)
    master_facets = np.asarray(master_facets, dtype=np.int64)
    if slave_facets.size == 0 or master_facets.size == 0:
        raise ValueError(f"contact pair {name!r}: empty slave ({slave_facets.size}) or master "
                         f"({master_facets.size}) facet set")
    ndof = basis.N if ndof is None else int(ndof)
    scalar = basis.elem.elem
    edofs = Dofs(mesh, scalar).element_dofs

    # slave integration points
    Xs, ns, area = _facet_frame(mesh.p, mesh.facets[:, slave_facets])
    ns, s_parent = _outward(mesh, slave_facets, ns)
    qx, qw = get_quadrature(RefTri, intorder)  # reference triangle (0,0),(1,0),(0,1); Σw = 1/2
    nq = qw.size
    lam = np.vstack([1.0 - qx[0] - qx[1], qx[0], qx[1]])  # (3, nq) barycentric
    pts = np.einsum("cq,xcf->fqx", lam, Xs).reshape(-1, 3)
    w = (2.0 * area[:, None] * qw[None, :]).ravel()
    sf = np.repeat(slave_facets, nq)
    s_tet = np.repeat(s_parent, nq)

    # closest master facet among the search_k nearest centroids
    Xm, nm, _ = _facet_frame(mesh.p, mesh.facets[:, master_facets])
    nm, m_parent = _outward(mesh, master_facets, nm)
    cent = Xm.mean(axis=1).T
    k = int(min(search_k, master_facets.size))
    _, cand = cKDTree(cent).query(pts, k=k)
    cand = cand.reshape(pts.shape[0], k)
    A = Xm[:, 0, cand.ravel()].T
    B = Xm[:, 1, cand.ravel()].T
    C = Xm[:, 2, cand.ravel()].T
    xr = np.repeat(pts, k, axis=0)
    cp, dist = _closest_on_triangles(xr, A, B, C)
    dist = dist.reshape(-1, k)
    best = np.argmin(dist, axis=1)
    mloc = cand[np.arange(pts.shape[0]), best]
    xm = cp.reshape(-1, k, 3)[np.arange(pts.shape[0]), best]
    n = nm[mloc]
    # tangents: t1 along the projection of the least-aligned axis, t2 = n × t1
    ax = np.eye(3)[np.argmin(np.abs(n), axis=1)]
    t1 = ax - np.einsum("ij,ij->i", ax, n)[:, None] * n
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    t2 = np.cross(n, t1)
    g0 = np.einsum("ij,ij->i", pts - xm, n) + float(clearance)
    m_tet = m_parent[mloc]

    frames = np.stack([n, t1, t2], axis=1)  # (m, 3, 3)
    S = _shape_operator(mesh, scalar, edofs, s_tet, pts, ndof, frames)
    M = _shape_operator(mesh, scalar, edofs, m_tet, xm, ndof, frames)
    D = sp.csr_matrix(S - M)
    m = pts.shape[0]
    B_n = sp.csr_matrix(D[np.arange(m) * 3])
    rows_t = (np.arange(m)[:, None] * 3 + np.array([1, 2])[None, :]).ravel()
    B_t = sp.csr_matrix(D[rows_t])

    def per_point(v, what):
        v = np.asarray(v, dtype=float)
        if v.ndim == 0:
            return np.full(m, float(v))
        if v.shape != slave_facets.shape:
            raise ValueError(f"contact pair {name!r}: {what} must be scalar or one per slave facet "
                             f"({slave_facets.size}), got shape {v.shape}")
        return np.repeat(v, nq)

    pn = per_point(penalty_n, "penalty_n")
    pt = pn.copy() if penalty_t is None else per_point(penalty_t, "penalty_t")
    if np.any(pn <= 0) or np.any(pt <= 0):
        raise ValueError(f"contact pair {name!r}: penalties must be > 0 Pa/m")
    if friction < 0:
        raise ValueError(f"contact pair {name!r}: friction coefficient = {friction}; expected >= 0")
    pdist = np.linalg.norm(pts - xm, axis=1)
    log.info("pair %s: %d slave points on %d facets -> %d master facets; g0 in [%.3g, %.3g] m",
             name, m, slave_facets.size, master_facets.size, g0.min(), g0.max())
    return ContactPair(name=name, points=pts, weights=w, g0=g0, normal=n, t1=t1, t2=t2, B_n=B_n, B_t=B_t,
                       penalty_n=pn, penalty_t=pt, friction=float(friction), slave_facet=sf,
                       master_facet=master_facets[mloc], projection_distance=pdist)


def default_penalty(mesh, slave_facets, E: float, factor: float = 10.0) -> np.ndarray:
    """Penalty per slave facet ε = factor · E / h (Pa/m), h = sqrt(2 · facet area) (local element size).

    The augmented-Lagrangian update makes the converged gap independent of this value; it only sets
    how many Uzawa updates are needed (larger = fewer, but worse conditioning).
    """
    _, _, area = _facet_frame(mesh.p, mesh.facets[:, np.asarray(slave_facets, dtype=np.int64)])
    return factor * float(E) / np.sqrt(2.0 * area)
