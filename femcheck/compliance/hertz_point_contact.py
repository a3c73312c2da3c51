"""Hertz point contact of the spherical joint: ball on a seat (seed 000 eqs. 27-35; Johnson, Contact
Mechanics, §4.2; docs/conventions.md §5 "Spherical joint").

    1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2,    1/R* = 1/R_ball + kappa_seat
    F = (4/3) E* sqrt(R*) delta^(3/2)                      (force-approach law)
    k(F) = dF/ddelta = 2 E* sqrt(R* delta) = (6 E*^2 R* F)^(1/3)   (tangent stiffness)

Seed 000 writes this with E' = 2 E* and R' = R*/2; its stiffness E' (2 R' delta)^(1/2) at the force of
its eq. 27 equals (6 E*^2 R* F)^(1/3) exactly, so only the notation differs.

:func:`hertz_tangent_stiffness` is THE implementation of the Hertz point-contact stiffness law: the numpy chain
models call it, and the compiled chain kernel
(:mod:`femcheck.parallel.chain_kernel`) calls the function this module holds when it runs, compiled by
:func:`femcheck.compliance.kernel_laws.kernel_laws` (a numba-compatible leaf: scalars or numpy arrays, no
allocation). :func:`effective_modulus` and :func:`effective_radius` are THE E* and R* of the analytical model.
"""
from __future__ import annotations

import numpy as np
from numba.extending import register_jitable


def effective_modulus(E1, nu1, E2, nu2):
    """Contact modulus E* (Pa): 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2."""
    return 1.0 / ((1.0 - np.square(nu1)) / E1 + (1.0 - np.square(nu2)) / E2)


def effective_radius(ball_radius, seat_curvature=0.0):
    """Effective radius R* (m): 1/R* = 1/R_ball + kappa_seat (kappa = 0 flat seat; concave seat -1/R_s)."""
    return 1.0 / (1.0 / np.asarray(ball_radius, dtype=float) + seat_curvature)


def hertz_force(delta, E_star, R_star):
    """Normal force F (N) at mutual approach ``delta`` (m): F = (4/3) E* sqrt(R*) delta^1.5."""
    return 4.0 / 3.0 * E_star * np.sqrt(R_star) * np.power(np.clip(delta, 0.0, None), 1.5)


@register_jitable
def hertz_tangent_stiffness(F, E_star, R_star):
    """Tangent normal stiffness k = dF/d delta = (6 E*^2 R* F)^(1/3) (N/m) at force ``F`` (N); scalars or arrays
    (broadcast), also callable from numba-compiled code."""
    return np.cbrt(6.0 * (E_star * E_star) * R_star * F)


def spherical_joint_compliance(k_sp) -> np.ndarray:
    """Local 6x6 compliance of the spherical joint (seed 000 eq. 35): diag(1/k, 1/k, 1/k, 0, 0, 0).

    Translational and isotropic; the joint's rotations are handled by the joint idealization
    (rigid: no rotational compliance; released: free rotations), not here.
    """
    k_sp = np.asarray(k_sp, dtype=float)
    S = np.zeros(k_sp.shape + (6, 6))
    S[..., 0, 0] = S[..., 1, 1] = S[..., 2, 2] = 1.0 / k_sp
    return S
