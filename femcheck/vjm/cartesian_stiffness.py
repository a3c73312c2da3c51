"""Cartesian compliance and stiffness of a serial VJM model, complementary stiffness, deflection.

Physics. Each (virtual) joint j is a torsion spring of stiffness k_j about its axis. A wrench
``F = [f; m]`` (N, N m; base frame, at the tool point) loads the joints with ``tau = J^T F`` and the
springs twist by ``dtheta = K_theta^-1 tau``; the tool twist is ``dX = J dtheta`` (seed 003 eqs. 10-15,
seed 002 eqs. 1-3, 7-8)::

    C = J K_theta^-1 J^T                      (6 x 6, compliance, m/N ... rad/(N m))

When the load is large enough for the change of J with the posture to matter, differentiating
``tau = J(theta)^T F`` gives the complementary stiffness (seed 002 eq. 4, seed 003 eq. 13)::

    K_C = [dJ^T/dtheta_1 F, ..., dJ^T/dtheta_n F]        (n x n, N m/rad)
    K   = J^-T (K_theta - K_C) J^-1                         (seed 002 eq. 5, seed 003 eq. 12)

We never invert J (it is singular at the wrist singularities of seed 003 Table 6, postures 1 and 3, and
not square for redundant or extended chains): the compliance ``C = J (K_theta - K_C)^-1 J^T`` is the
same matrix as ``K^-1`` whenever J is square and invertible, and stays defined when it is not.
The deflection under the wrench is ``dX = C F`` (seed 003 eq. 15): ``[dx, dy, dz, rx, ry, rz]`` in m and rad
(small rotation vector).

K_C is computed in closed form for revolute joints ordered from the base: joint i carries the axes of the
joints after it rigidly, so for the column of joint j and the variable theta_i::

    i <= j:  d z_j = z_i x z_j,  d(z_j x (p - o_j)) = z_i x (z_j x (p - o_j))
    i >  j:  d z_j = 0,          d(z_j x (p - o_j)) = z_j x (z_i x (p - o_i))

and ``K_C[j, i] = f . d(J_v,j) + m . d(J_w,j)``. It is not symmetric when the wrench holds a moment.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

log = logging.getLogger(__name__)


def complementary_stiffness(axes: np.ndarray, origins: np.ndarray, point: np.ndarray, wrench: np.ndarray) -> np.ndarray:
    """K_C = dJ^T/dtheta F for revolute joints (seed 002 eq. 4, seed 003 eq. 13).

    ``axes``, ``origins`` (m, k, 3) joint axes (unit) and points on them, ordered base to tip; ``point``
    (m, 3) tool point, m; ``wrench`` (6,) or (m, 6) ``[f; m]`` in N and N m, base frame, at the tool point.
    Returns (m, k, k) in N m/rad; entry [j, i] = d(J_j . F)/d theta_i.
    """
    m_, k, _ = axes.shape
    W = np.broadcast_to(np.asarray(wrench, dtype=float), (m_, 6))
    f, mom = W[:, None, :3], W[:, None, 3:]
    jv = np.cross(axes, point[:, None, :] - origins)       # (m, k, 3) J_v columns
    fz = np.cross(f, axes)                                 # f x z_i
    mz = np.cross(mom, axes)                               # m x z_i
    # i <= j: f.(z_i x Jv_j) + m.(z_i x z_j) = Jv_j.(f x z_i) + z_j.(m x z_i)
    prox = np.einsum("mjc,mic->mji", jv, fz) + np.einsum("mjc,mic->mji", axes, mz)
    # i > j: f.(z_j x Jv_i) = Jv_i.(f x z_j)
    dist = np.einsum("mic,mjc->mji", jv, fz)
    lower = np.tril(np.ones((k, k), dtype=bool))[None]     # [j, i] with i <= j
    return np.where(lower, prox, dist)


def cartesian_compliance(J: np.ndarray, k_theta, K_C: np.ndarray | None = None) -> np.ndarray:
    """C = J (K_theta - K_C)^-1 J^T, (m, 6, 6) (seed 003 eq. 15; seed 002 eqs. 5, 7).

    ``J`` (m, 6, k); ``k_theta`` (k,) joint stiffnesses in N m/rad (or a (k, k) / (m, k, k) matrix);
    ``K_C`` optional (m, k, k) complementary stiffness. Without K_C this is ``J diag(1/k) J^T``.
    """
    J = np.asarray(J, dtype=float)
    Kt = np.asarray(k_theta, dtype=float)
    if K_C is None and Kt.ndim == 1:
        return np.einsum("mik,k,mjk->mij", J, 1.0 / Kt, J)
    Kmat = np.diag(Kt) if Kt.ndim == 1 else Kt
    Keff = np.broadcast_to(Kmat, J.shape[:1] + Kmat.shape[-2:]) - (0.0 if K_C is None else K_C)
    X = np.linalg.solve(Keff, np.swapaxes(J, -1, -2))       # (m, k, 6) = (K_theta - K_C)^-1 J^T
    return J @ X


def cartesian_stiffness(C: np.ndarray, rcond: float = 1e-12) -> tuple[np.ndarray, np.ndarray]:
    """K = C^-1 (seed 002 eq. 5 / seed 003 eq. 14) and the rank of C, per pose.

    At a singular posture (rank C < 6) the stiffness is unbounded along the twist the chain cannot make;
    there the Moore-Penrose pseudo-inverse is returned (zero stiffness along that direction, to be read with
    the rank). Returns ``(K (m, 6, 6), rank (m,))``.
    """
    C = np.asarray(C, dtype=float)
    s = np.linalg.svd(C, compute_uv=False)
    rank = np.sum(s > rcond * s[..., :1], axis=-1)
    full = rank == 6
    K = np.empty_like(C)
    if full.any():
        K[full] = np.linalg.inv(C[full])
    if (~full).any():
        log.debug("%d singular posture(s): pseudo-inverse stiffness", int((~full).sum()))
        K[~full] = np.linalg.pinv(C[~full], rcond=rcond)
    return K, rank


@dataclass(frozen=True)
class Deflection:
    """Result of a VJM deflection computation for m poses.

    ``twist`` (m, 6) [dx, dy, dz, rx, ry, rz] m and rad; ``C`` (m, 6, 6) compliance; ``K`` (m, 6, 6)
    stiffness (pseudo-inverse where ``rank`` < 6); ``K_C`` (m, k, k) or None; ``joint_torque`` (m, k) N m;
    ``joint_deflection`` (m, k) rad.
    """

    twist: np.ndarray
    C: np.ndarray | None
    K: np.ndarray | None
    rank: np.ndarray | None
    K_C: np.ndarray | None
    joint_torque: np.ndarray
    joint_deflection: np.ndarray


def deflection(J: np.ndarray, k_theta, wrench, K_C: np.ndarray | None = None, stiffness: bool = True) -> Deflection:
    """Tool twist under ``wrench`` (6,) or (m, 6): dX = J (K_theta - K_C)^-1 J^T F (seed 003 eq. 15, seed 002 eq. 5).

    ``stiffness=False`` skips C, K and the rank (they are then None): the fast path for deflections only.
    """
    J = np.asarray(J, dtype=float)
    m = J.shape[0]
    W = np.broadcast_to(np.asarray(wrench, dtype=float), (m, 6))
    tau = np.einsum("mik,mi->mk", J, W)
    Kt = np.asarray(k_theta, dtype=float)
    if K_C is None and Kt.ndim == 1:
        dtheta = tau / Kt
    else:
        Kmat = np.diag(Kt) if Kt.ndim == 1 else Kt
        Keff = np.broadcast_to(Kmat, (m,) + Kmat.shape[-2:]) - (0.0 if K_C is None else K_C)
        dtheta = np.linalg.solve(Keff, tau[..., None])[..., 0]
    twist = np.einsum("mik,mk->mi", J, dtheta)
    C = K = rank = None
    if stiffness:
        C = cartesian_compliance(J, k_theta, K_C)
        K, rank = cartesian_stiffness(C)
    return Deflection(twist=twist, C=C, K=K, rank=rank, K_C=K_C, joint_torque=tau, joint_deflection=dtheta)
