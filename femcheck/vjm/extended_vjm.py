"""Extended VJM (seed 002): three virtual joints per actuated joint, and identification of their compliances.

Model. Besides the torsion spring about its axis (z), every actuated joint gets two tilt springs about
the x and y axes of its joint frame (the frame whose z is the joint axis, that turns with the joint, see
:class:`femcheck.vjm.dh.ChainPoses`). They lump the compliance of the link, the bearings and the housing
(seed 002 sec. II, Fig. 1a, Fig. 2). An n-joint arm has 3n virtual joints, ordered joint by joint as
(torsion, tilt x, tilt y); each tilt joint is carried by the torsion joint before it.

Identification (seed 002 eqs. 8-12). With the complementary stiffness neglected, the tool deflection is
``dX = J C_theta J^T F`` with ``C_theta = diag(c)``. It is linear in the compliances::

    dX_r = sum_j c_j J_rj (J_:j . F)  =>  A(J, F) c = dX,   A_rj = J_rj sum_i J_ij F_i       (eqs. 9-10)

Stacking k configurations x p wrenches (only the translational rows when orientations are not measured, as
in the seed) gives an over-determined system solved in the least-squares sense (eqs. 11-12)::

    c_min = argmin 1/2 |A c - dX|^2 = (A^T A)^-1 A^T dX

Here it is solved with an orthogonal factorization (``numpy.linalg.lstsq``), which gives the same c as
eq. 12 without squaring the condition number. Error sensitivity is ruled by cond(A) (2-norm); a set of
measurement configurations is scored by it and can be chosen greedily to keep it small (seed 002 sec. IV-A).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from femcheck.vjm.dh import ChainPoses, DHChain, forward_kinematics, screw_jacobian

log = logging.getLogger(__name__)

#: names of the three virtual joints of an actuated joint, in order
VIRTUAL_KINDS = ("torsion", "tilt_x", "tilt_y")


def virtual_joint_axes(fk: ChainPoses, extended: bool = True, tilt_offset_m=None) -> tuple[np.ndarray, np.ndarray]:
    """Axes and origins of the virtual joints, (m, 3n, 3) each (or (m, n, 3) when ``extended`` is False).

    Order per joint: torsion (joint-frame z), tilt about joint-frame x, tilt about joint-frame y. The tilt
    springs sit on the joint axis at ``tilt_offset_m`` (n,) m from the joint-frame origin (default 0): where
    consecutive joint axes intersect (every 7-joint cobot with spherical shoulder, elbow and wrist), tilts at
    the intersection point coincide with the next joint's torsion and cannot be told apart; an offset (the
    bearing's place in the housing) separates them.
    """
    if not extended:
        return fk.axes, fk.origins
    R = fk.joint_frames[..., :3, :3]                       # (m, n, 3, 3); columns x, y, z
    axes = np.stack([R[..., :, 2], R[..., :, 0], R[..., :, 1]], axis=2)   # (m, n, 3, 3)
    m, n = axes.shape[:2]
    off = np.zeros(n) if tilt_offset_m is None else np.asarray(tilt_offset_m, dtype=float)
    tilt_origin = fk.origins + off[None, :, None] * R[..., :, 2]
    origins = np.stack([fk.origins, tilt_origin, tilt_origin], axis=2)
    return axes.reshape(m, 3 * n, 3), origins.reshape(m, 3 * n, 3)


def virtual_jacobian(chain: DHChain, q, extended: bool = True, tilt_offset_m=None) -> np.ndarray:
    """(m, 6, 3n) Jacobian of the virtual joints at the tool point (or (m, 6, n) when not extended)."""
    fk = forward_kinematics(chain, q)
    axes, origins = virtual_joint_axes(fk, extended, tilt_offset_m)
    return screw_jacobian(axes, origins, fk.tcp)


def identification_matrix(J: np.ndarray, wrenches: np.ndarray, rows: str = "translation") -> np.ndarray:
    """Stacked A(J, F) of seed 002 eq. 10.

    ``J`` (m, 6, k) virtual-joint Jacobians of the m measurements; ``wrenches`` (m, 6) N and N m. ``rows``:
    ``"translation"`` keeps the first three rows of each block (seed 002: orientations are not measured),
    ``"full"`` keeps all six. Returns (m * r, k) with r = 3 or 6; units m/(rad/(N m)) and rad/(rad/(N m)).
    """
    J = np.asarray(J, dtype=float)
    W = np.asarray(wrenches, dtype=float)
    tau = np.einsum("mik,mi->mk", J, W)                    # (m, k) = J^T F
    A = J * tau[:, None, :]                                 # (m, 6, k): A_rj = J_rj tau_j
    r = {"translation": 3, "full": 6}[rows]
    return A[:, :r, :].reshape(-1, J.shape[2])


@dataclass(frozen=True)
class Identification:
    """Result of the least-squares identification: ``compliance`` (k,) rad/(N m); ``stiffness`` (k,) N m/rad;
    ``condition_number`` of A; ``rank`` of A; ``residual_rms_m`` of A c - dX; ``standard_error`` (k,) of c
    estimated from the residual (classical LS: s^2 (A^T A)^-1)."""

    compliance: np.ndarray
    stiffness: np.ndarray
    condition_number: float
    rank: int
    residual_rms_m: float
    standard_error: np.ndarray


def identify_compliances(J: np.ndarray, wrenches: np.ndarray, displacements: np.ndarray,
                         rows: str = "translation") -> Identification:
    """Least-squares virtual-joint compliances from measured tool deflections (seed 002 eqs. 10-12).

    ``J`` (m, 6, k); ``wrenches`` (m, 6); ``displacements`` (m, 3) or (m, 6) measured twists (m, rad),
    matching ``rows``. Raises ValueError when A has fewer rows than unknowns.
    """
    A = identification_matrix(J, wrenches, rows)
    r = 3 if rows == "translation" else 6
    b = np.asarray(displacements, dtype=float)[:, :r].reshape(-1)
    if A.shape[0] < A.shape[1]:
        raise ValueError(f"{A.shape[0]} equations for {A.shape[1]} compliances; add configurations or wrenches")
    c, _, rank, sv = np.linalg.lstsq(A, b, rcond=None)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    if rank < A.shape[1]:
        log.warning("identification matrix has rank %d < %d unknowns: some compliances are not identifiable", rank, A.shape[1])
    res = A @ c - b
    dof = max(A.shape[0] - A.shape[1], 1)
    s2 = float(res @ res) / dof
    cov = s2 * np.linalg.pinv(A.T @ A)
    with np.errstate(divide="ignore"):
        stiff = 1.0 / c
    return Identification(compliance=c, stiffness=stiff, condition_number=cond, rank=int(rank),
                          residual_rms_m=float(np.sqrt(np.mean(res**2))), standard_error=np.sqrt(np.clip(np.diag(cov), 0, None)))


def condition_number(J: np.ndarray, wrenches: np.ndarray, rows: str = "translation") -> float:
    """2-norm condition number of the stacked identification matrix A (seed 002 Table I scores configurations)."""
    sv = np.linalg.svd(identification_matrix(J, wrenches, rows), compute_uv=False)
    return float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")


def select_configurations(J: np.ndarray, wrenches: np.ndarray, count: int, rows: str = "translation") -> tuple[np.ndarray, float]:
    """Greedy choice of ``count`` candidate configurations that keeps cond(A) small.

    ``J`` (N, 6, k) candidate Jacobians; ``wrenches`` (p, 6) the wrenches applied at every chosen
    configuration. Starts from the candidate set with the largest smallest singular value reachable by
    adding one configuration at a time; returns (indices (count,), cond). Cost: O(count N) SVDs.
    """
    J = np.asarray(J, dtype=float)
    W = np.asarray(wrenches, dtype=float)
    N, p = J.shape[0], W.shape[0]
    blocks = np.stack([identification_matrix(np.repeat(J[i:i + 1], p, 0), W, rows) for i in range(N)])  # (N, p r, k)
    chosen: list[int] = []
    best_cond = float("inf")
    for _ in range(count):
        best, best_score = -1, None
        for i in range(N):
            if i in chosen:
                continue
            A = np.concatenate([blocks[j] for j in chosen + [i]])
            sv = np.linalg.svd(A, compute_uv=False)
            k = min(A.shape)
            # rank-deficient stacks are ranked by how many singular values are non-zero, then by the smallest one
            nz = int(np.sum(sv > sv[0] * 1e-12))
            score = (nz, sv[k - 1] / sv[0])
            if best_score is None or score > best_score:
                best, best_score = i, score
        chosen.append(best)
    A = np.concatenate([blocks[j] for j in chosen])
    sv = np.linalg.svd(A, compute_uv=False)
    best_cond = float(sv[0] / sv[-1]) if sv[-1] > 0 and A.shape[0] >= A.shape[1] else float("inf")
    return np.array(chosen), best_cond
