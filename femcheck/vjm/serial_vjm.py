"""A serial robot's VJM model (chain + virtual-joint stiffnesses) and its deflection under a tool wrench.

Conventional VJM (seed 003): one torsion spring per actuated joint, ``k_theta`` (n,). Extended VJM
(seed 002): three springs per joint (torsion, tilt x, tilt y of the joint frame), ``k_theta`` (3n,),
ordered joint by joint. The deflection is ``dX = J (K_theta - K_C)^-1 J^T F`` (see
:mod:`femcheck.vjm.cartesian_stiffness`), with K_C from the wrench when ``complementary`` is true.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from femcheck.vjm.cartesian_stiffness import Deflection, complementary_stiffness, deflection
from femcheck.vjm.dh import DHChain, forward_kinematics, screw_jacobian
from femcheck.vjm.extended_vjm import virtual_joint_axes


@dataclass(frozen=True)
class SerialVJM:
    """Immutable VJM model: ``chain``; ``k_theta`` virtual-joint stiffnesses, N m/rad ((n,) or (3n,) when
    ``extended``); ``tilt_offset_m`` (n,) place of the tilt springs along each joint axis, m."""

    chain: DHChain
    k_theta: tuple[float, ...]
    extended: bool = False
    tilt_offset_m: tuple[float, ...] | None = None

    def __post_init__(self):
        n = self.chain.n_joints
        want = 3 * n if self.extended else n
        if len(self.k_theta) != want:
            raise ValueError(f"k_theta has {len(self.k_theta)} entries; expected {want}")

    @property
    def n_virtual(self) -> int:
        return len(self.k_theta)


def virtual_geometry(model: SerialVJM, q) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(axes (m, k, 3), origins (m, k, 3), tcp (m, 3)) of the model's virtual joints at poses q (m, n) rad."""
    fk = forward_kinematics(model.chain, q)
    axes, origins = virtual_joint_axes(fk, model.extended, model.tilt_offset_m)
    return axes, origins, fk.tcp


def deflect(model: SerialVJM, q, wrench, complementary: bool = True, stiffness: bool = True) -> Deflection:
    """Tool twist (m, 6) [m, rad] under ``wrench`` (6,) or (m, 6) [N, N m] at poses ``q`` (m, n) rad.

    ``complementary`` adds K_C (seed 002 eq. 5); False gives seed 003 eq. 15 (K_C neglected).
    ``stiffness=False`` returns the twist only (no C, K, rank): the fast path for large batches.
    """
    axes, origins, tcp = virtual_geometry(model, q)
    J = screw_jacobian(axes, origins, tcp)
    KC = complementary_stiffness(axes, origins, tcp, np.asarray(wrench, dtype=float)) if complementary else None
    return deflection(J, np.asarray(model.k_theta), wrench, KC, stiffness=stiffness)
