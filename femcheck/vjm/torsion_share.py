"""Share of the tool deflection that the joint torsion springs cause (seed 002 §V, Fig. 5).

Without the complementary stiffness the VJM deflection is a sum over the virtual springs,
``dX = sum_j J_j (J_j^T W) / k_j`` (J_j the unit twist of spring j at the tool point), so the deflection
splits exactly into the torsion springs' part ``dX_t`` and the tilt springs' part. The share reported is
the projection ``dX_t . dX / |dX|^2`` of the translation, which is additive (torsion + tilt = 1). Seed 002
reports 76.5 % on average over its 13 configurations, 88.1 % at most (configuration 9) and 44.9 % at least
(configuration 11, singular), for the SHIR5 arm, whose geometry it does not publish.
"""
from __future__ import annotations

import numpy as np

from femcheck.vjm.dh import screw_jacobian
from femcheck.vjm.serial_vjm import SerialVJM, virtual_geometry


def spring_deflections(model: SerialVJM, q, wrench) -> np.ndarray:
    """(m, 3, k) tool translation caused by each virtual spring (m), without K_C: column j is
    ``J_j (J_j^T W) / k_j``; their sum is the VJM deflection."""
    axes, origins, tcp = virtual_geometry(model, np.atleast_2d(q))
    J = screw_jacobian(axes, origins, tcp)                                   # (m, 6, k)
    W = np.broadcast_to(np.asarray(wrench, float), (J.shape[0], 6))
    return J[:, :3, :] * (np.einsum("mij,mi->mj", J, W) / np.asarray(model.k_theta))[:, None, :]


def torsion_share(model: SerialVJM, q, wrench) -> np.ndarray:
    """(m,) torsion share of the translational tool deflection at poses ``q`` (m, n) rad under ``wrench``
    (6,) or (m, 6) N, N m. ``model`` must be extended (springs ordered torsion, tilt x, tilt y per joint)."""
    if not model.extended:
        raise ValueError("torsion_share needs the extended VJM (three springs per joint)")
    per_spring = spring_deflections(model, q, wrench)
    total = per_spring.sum(axis=2)                                           # (m, 3)
    torsion = per_spring[:, :, 0::3].sum(axis=2)
    return np.einsum("mi,mi->m", torsion, total) / np.einsum("mi,mi->m", total, total)
