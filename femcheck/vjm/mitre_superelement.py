"""A mitred tube corner as a solid finite-element superelement: the corner's shell flexibility without a code factor.

The solid is the thin-walled tube of a :class:`~femcheck.vjm.beam_world.Tube` (its outer diameter, wall and
material), two straight legs of length ``leg_m`` joined at a single mitre: leg A runs along +x to the corner at
the origin, leg B leaves it along t_out = (cos alpha, sin alpha, 0), and the joint is the bisector plane (normal
t_in - t_out), where the two legs' cross-sections meet exactly. A straight tube (alpha = 0) is the same solid cut
square. Mesh: a structured hexahedral mesh mapped from (theta, u, rho) (circumference, along the generators from
end A over the mitre to end B, through the wall), triquadratic elements (skfem ``ElementHex2``: bending through a
single element layer is exact for a quadratic field), isotropic linear elasticity.

Each end is a rigid ring (RBE2): every node of the end face follows one master node at the face centre,
u = u_c + theta_c x (x - x_c). The interior is condensed onto the two masters (one Schur complement,
:func:`femcheck.fe.schur_complement.schur_complement`): a 12 x 12 stiffness S, configuration-independent,
cached on disk by its inputs (:mod:`femcheck.fe.result_cache`). Clamping end A leaves C_solid = S_BB^-1, the
compliance of end B (base frame of the superelement, [u; theta] under [F; M] at end B's centre).

The corner's own flexibility is what the solid has beyond the beam model's sharp rigid corner with the same legs
(:func:`femcheck.fe.beam.assemble_beam_stiffness`, Timoshenko, the same element the world uses):
C_solid - C_beam, carried to the corner as a 6 x 6 compliance D between the two tube ends that meet there:
a wrench W_B = [F; M] at end B is W_c = A W_B at the corner (F, M + r x F, r = x_B - x_c) and a corner motion
delta_c moves end B by A^T delta_c, so D = A^-T (C_solid - C_beam) A^-1.

The rigid rings stiffen the tube's ends (no ovalisation there), so a straight tube's superelement is a little
stiffer than the Timoshenko tube (:func:`straight_tube_check`); the legs are long enough (default 2.5 D) that
the corner's ovalisation has decayed before the rings.
"""
from __future__ import annotations

import functools
import hashlib
import logging
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp

log = logging.getLogger(__name__)

#: mesh defaults: elements around the circumference, along each leg, through the wall; legs in outer diameters
N_CIRC, N_LEG, N_WALL, LEG_DIAMETERS = 32, 12, 1, 2.5


@dataclass(frozen=True)
class MitreSuperelement:
    """Condensed solid of one mitred (or straight) tube: ``S`` (12, 12) stiffness on [u_A, theta_A, u_B, theta_B]
    (N/m, N, N m/rad), masters at ``x_A`` and ``x_B`` (3,) m; ``angle_rad`` (alpha), ``leg_m``; ``n_dof`` of the
    solid; ``t_in`` and ``t_out`` (3,) the legs' directions (superelement frame)."""

    S: np.ndarray
    x_A: np.ndarray
    x_B: np.ndarray
    t_in: np.ndarray
    t_out: np.ndarray
    angle_rad: float
    leg_m: float
    n_dof: int

    def compliance_B(self) -> np.ndarray:
        """(6, 6) compliance of end B with end A clamped, [u; theta] per [F; M] at x_B."""
        return np.linalg.inv(self.S[6:, 6:])


def _mesh(D: float, T: float, angle_rad: float, leg_m: float, n_circ: int, n_leg: int, n_wall: int):
    """MeshHex of the mitred tube (module docstring): tensor mesh in (theta, u, rho) mapped to space, the theta
    seam merged. Axial spacing graded toward the mitre (power 1.5), where the wall bends most."""
    from skfem import MeshHex
    th = np.linspace(0.0, 2 * math.pi, n_circ + 1)
    x = np.linspace(0.0, 1.0, n_leg + 1)
    u = np.r_[1 - (1 - x) ** 1.5, 1 + x[1:] ** 1.5]          # leg A 0..1, leg B 1..2, finer at the mitre (u = 1)
    rho = np.linspace(D / 2 - T, D / 2, n_wall + 1)
    m = MeshHex.init_tensor(th, u, rho)
    p = m.p.copy()
    theta, uu, r = p
    t_in = np.array([1.0, 0.0, 0.0])
    t_out = np.array([math.cos(angle_rad), math.sin(angle_rad), 0.0])
    normal = t_in - t_out if angle_rad > 0 else t_in                          # the cut plane through the corner
    w = np.array([np.zeros_like(theta), r * np.cos(theta), r * np.sin(theta)])   # offset in leg A's section
    s_m = -(normal @ w) / (normal @ t_in)                                    # leg A's generator meets the cut
    p_m = s_m * t_in[:, None] + w
    t_m = t_out @ p_m
    a = uu <= 1.0
    xyz = np.where(a, (-leg_m + uu * (s_m + leg_m)) * t_in[:, None] + w,
                   p_m + (uu - 1.0) * (leg_m - t_m) * t_out[:, None])
    # merge the seam theta = 2 pi onto theta = 0
    seam = np.isclose(theta, 2 * math.pi)
    key = {(round(x, 12), round(y, 12)): i for i, (x, y, th0) in enumerate(zip(uu, r, theta)) if th0 == 0.0}
    remap = np.arange(p.shape[1])
    for i in np.flatnonzero(seam):
        remap[i] = key[(round(uu[i], 12), round(r[i], 12))]
    keep = ~seam
    new = -np.ones(p.shape[1], dtype=int)
    new[keep] = np.arange(keep.sum())
    t = new[remap[m.t]]
    # contiguous arrays: skfem otherwise copies them itself and logs a warning for every mesh
    return MeshHex(np.ascontiguousarray(xyz[:, keep]), np.ascontiguousarray(t)), t_in, t_out


def _rigid_ring_rows(x: np.ndarray, comp: np.ndarray, xc: np.ndarray) -> np.ndarray:
    """(n, 6) rows of u_k = e_k . (u_c + theta_c x (x - x_c)) = [e_k, (x - x_c) x e_k] for DOFs of component k."""
    e = np.eye(3)[comp]
    return np.c_[e, np.cross(x - xc, e)]


def _source_hash() -> str:
    return hashlib.sha256(Path(__file__).read_bytes()).hexdigest()[:16]


def mitre_superelement(tube, angle_rad: float, leg_m: float | None = None, n_circ: int = N_CIRC,
                       n_leg: int = N_LEG, n_wall: int = N_WALL) -> MitreSuperelement:
    """The condensed solid of ``tube`` turned by ``angle_rad`` (0: straight) with legs ``leg_m`` (default 2.5 D)
    from the corner; read from the FE result cache when it holds the same inputs (module docstring)."""
    from femcheck.fe import result_cache
    leg = LEG_DIAMETERS * tube.outer_diameter_m if leg_m is None else leg_m
    inputs = {"D": tube.outer_diameter_m, "T": tube.wall_m, "E": tube.E_Pa, "nu": tube.nu, "angle": angle_rad,
              "leg": leg, "mesh": [n_circ, n_leg, n_wall], "source": _source_hash()}
    key = result_cache.result_key("mitre_superelement", inputs)
    got = result_cache.load("mitre_superelement", key)
    if got is not None:
        return got
    se = _build(tube, angle_rad, leg, n_circ, n_leg, n_wall)
    result_cache.store("mitre_superelement", key, se)
    return se


def _build(tube, angle_rad, leg, n_circ, n_leg, n_wall) -> MitreSuperelement:
    from skfem import Basis, ElementHex2, ElementVector
    from femcheck.fe.elasticity import assemble_stiffness
    from femcheck.fe.schur_complement import schur_complement

    mesh, t_in, t_out = _mesh(tube.outer_diameter_m, tube.wall_m, angle_rad, leg, n_circ, n_leg, n_wall)
    basis = Basis(mesh, ElementVector(ElementHex2()), intorder=4)     # 3 x 3 x 3 Gauss points
    K = assemble_stiffness(basis, tube.E_Pa, tube.nu)                 # vectorized isotropic elasticity
    n = K.shape[0]
    comp = np.empty(n, dtype=int)
    for arr in (basis.nodal_dofs, basis.edge_dofs, basis.facet_dofs, basis.interior_dofs):
        for k in range(3):
            comp[arr[k]] = k
    x = basis.doflocs.T
    x_A, x_B = -leg * t_in, leg * t_out
    tol = 1e-9 * leg
    ring_A = np.flatnonzero(np.abs((x - x_A) @ t_in) < tol)
    ring_B = np.flatnonzero(np.abs((x - x_B) @ t_out) < tol)
    free = np.setdiff1d(np.arange(n), np.r_[ring_A, ring_B])
    rows = np.r_[free, ring_A, ring_B]
    nf = len(free)
    GA = _rigid_ring_rows(x[ring_A], comp[ring_A], x_A)
    GB = _rigid_ring_rows(x[ring_B], comp[ring_B], x_B)
    P = sp.bmat([[sp.identity(nf), None, None], [None, sp.csr_matrix(GA), None], [None, None, sp.csr_matrix(GB)]],
                format="csr")
    perm = sp.csr_matrix((np.ones(n), (np.arange(n), rows)), shape=(n, n))   # u[rows] = P z
    Kz = (P.T @ (perm @ K @ perm.T) @ P).tocsr()
    S = schur_complement(Kz, np.arange(nf, nf + 12))
    S = 0.5 * (S + S.T)
    log.info("mitre superelement D %.3f T %.4f angle %.1f deg: %d DOFs", tube.outer_diameter_m, tube.wall_m,
             math.degrees(angle_rad), n)
    return MitreSuperelement(S=S, x_A=x_A, x_B=x_B, t_in=t_in, t_out=t_out, angle_rad=angle_rad, leg_m=leg, n_dof=n)


def beam_compliance_B(tube, se: MitreSuperelement) -> np.ndarray:
    """(6, 6) compliance of end B of the beam model of the same legs, a sharp rigid corner at the origin, end A
    clamped (Timoshenko elements of the world, :func:`femcheck.fe.beam.assemble_beam_stiffness`)."""
    from femcheck.fe.beam import assemble_beam_stiffness
    pts = [se.x_A, np.zeros(3), se.x_B] if se.angle_rad > 0 else [se.x_A, se.x_B]
    nodes = np.array(pts)
    el = np.array([[i, i + 1] for i in range(len(pts) - 1)])
    K = assemble_beam_stiffness(nodes, el, tube.E_Pa, tube.G_Pa, tube.section, shear=True).toarray()
    Kf = K[6:, 6:]
    return np.linalg.inv(Kf)[-6:, -6:]


@functools.lru_cache(maxsize=32)
def corner_excess_compliance(tube, angle_rad: float, **mesh) -> np.ndarray:
    """(6, 6) compliance D of the corner in the superelement frame (t_in = x, the bend in the x-y plane):
    A^-T (C_solid - C_beam) A^-1 with r = x_B (module docstring), symmetrized; kept in memory per process
    (read-only: do not modify the returned array)."""
    se = mitre_superelement(tube, angle_rad, **mesh)
    dC = se.compliance_B() - beam_compliance_B(tube, se)
    A = np.eye(6)
    r = se.x_B
    A[3:, :3] = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    Ai = np.linalg.inv(A)
    Dc = Ai.T @ dC @ Ai
    return 0.5 * (Dc + Dc.T)
