"""VJM of a parallel manipulator with passive joints (seed 001 eqs. 2-6).

Each leg i is a serial chain from the base to the platform point P. Its flexible links are 6-DOF virtual
springs (``K_theta,i``, block-diagonal over the links, each block a 6x6 link stiffness at the link's distal
end in the link frame); its active joints are locked (rigid); its passive joints have zero stiffness. A
small twist of the platform at P is (seed 001 eq. 2)::

    dX_i = J_theta,i dtheta_i + J_phi,i dphi_i

and the static balance of virtual springs and free passive joints gives the bordered system (eq. 5)::

    [ J_theta K_theta^-1 J_theta^T   J_phi ] [ F    ]   [ dX ]
    [ J_phi^T                         0    ] [ dphi ] = [ 0  ]

whose inverse has the leg's Cartesian stiffness K_i (6x6) as its upper-left block (eq. 6). K_i is
symmetric positive semi-definite with rank ``6 - rank(J_phi)``: the passive joints leave the leg free
along their twists. The legs act in parallel on the rigid platform, so ``K = sum_i K_i``.
The same block equals ``C^-1 - C^-1 J_phi (J_phi^T C^-1 J_phi)^-1 J_phi^T C^-1`` with ``C = J_theta K_theta^-1 J_theta^T``
(Schur complement), used by the tests as the second route.

Units: forces N, moments N m, translations m, rotations rad; stiffness blocks N/m, N/rad, N m/rad.
"""
from __future__ import annotations

import numpy as np

from femcheck.kinematics.frames import rot6, twist_shift


def link_jacobian(point: np.ndarray, link_origin: np.ndarray, link_axes: np.ndarray) -> np.ndarray:
    """(m, 6, 6) map of a link's 6-DOF virtual deflection ``[d; theta]`` (in its frame at ``link_origin``)
    to the twist at ``point``: ``Jf(point - origin)^T Rot(R)``.

    ``point``, ``link_origin`` (m, 3) m; ``link_axes`` (m, 3, 3) rotation whose columns are the link axes.
    """
    return twist_shift(point - link_origin) @ rot6(link_axes)


def passive_jacobian(axes: np.ndarray, origins: np.ndarray, point: np.ndarray) -> np.ndarray:
    """(m, 6, p) twists at ``point`` of unit rates of passive revolute joints (axes, origins (m, p, 3))."""
    v = np.cross(axes, point[:, None, :] - origins)
    return np.concatenate([v, axes], axis=-1).transpose(0, 2, 1)


def leg_compliance(J_theta: np.ndarray, K_theta: np.ndarray) -> np.ndarray:
    """C_theta,i = J_theta K_theta^-1 J_theta^T, (m, 6, 6) (upper-left block of seed 001 eq. 5).

    ``J_theta`` (m, 6, k); ``K_theta`` (k, k) or (m, k, k) symmetric positive definite.
    """
    K = np.broadcast_to(K_theta, J_theta.shape[:1] + K_theta.shape[-2:])
    return J_theta @ np.linalg.solve(K, np.swapaxes(J_theta, -1, -2))


def leg_stiffness(J_theta: np.ndarray, K_theta: np.ndarray, J_passive: np.ndarray) -> np.ndarray:
    """Leg Cartesian stiffness K_i (m, 6, 6): upper-left 6x6 block of the inverse of the bordered compliance
    matrix (seed 001 eqs. 5-6). ``J_passive`` (m, 6, p)."""
    C = leg_compliance(J_theta, K_theta)
    m, _, p = J_passive.shape
    B = np.zeros((m, 6 + p, 6 + p))
    B[:, :6, :6] = C
    B[:, :6, 6:] = J_passive
    B[:, 6:, :6] = np.swapaxes(J_passive, -1, -2)
    K = np.linalg.inv(B)[:, :6, :6]
    return 0.5 * (K + np.swapaxes(K, -1, -2))


def platform_stiffness(leg_stiffnesses) -> np.ndarray:
    """K = sum_i K_i over legs (seed 001 sec. 2.2); ``leg_stiffnesses`` (legs, m, 6, 6) -> (m, 6, 6)."""
    return np.sum(np.asarray(leg_stiffnesses), axis=0)


def parallel_stiffness(J_theta: np.ndarray, K_theta: np.ndarray, J_passive: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Leg and platform stiffness for identical legs: ``J_theta`` (L, m, 6, k), ``K_theta`` (k, k) shared by the
    legs, ``J_passive`` (L, m, 6, p). Returns (K_legs (L, m, 6, 6), K (m, 6, 6))."""
    L, m = J_theta.shape[:2]
    K_legs = leg_stiffness(J_theta.reshape((L * m,) + J_theta.shape[2:]), K_theta,
                           J_passive.reshape((L * m,) + J_passive.shape[2:])).reshape(L, m, 6, 6)
    return K_legs, platform_stiffness(K_legs)
