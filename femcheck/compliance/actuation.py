"""Actuation: cable in series with the motor shaft torsion reflected through the capstan
(seed 000 eqs. 43-46; docs/conventions.md §5 "Actuation").

    k_cable = E_c (pi d_c^2 / 4) / l_c                         axial rope stiffness (N/m)
    K_rotor = G (pi d_s^4 / 32) / L_s                          shaft torsion (N m / rad)
    k_motor = K_rotor / r_cap^2                                 torsion seen as a linear spring at the cable
    c_act = 1/k_cable + 1/k_motor,  S_act = c_act [e e^T, 0; 0, 0]   (translation along the rail e)

The paper puts 1/K_rotor on a rotational entry and sums stiffnesses (eq. 46); the motor torsion acts
through the capstan in series with the cable, so compliances add ([DEV] in docs/conventions.md). The
position loop is taken as ideal (no servo stiffness).

:func:`cable_stiffness` and :func:`motor_stiffness_at_cable` are THE implementations of the cable and the motor
shaft laws: :func:`femcheck.chain.device_parameters` and the parallel-device actuation read them from this module
when they run (the compiled kernels receive c_act as a parameter). The device FE does not use them (it meshes the
actuation, or restates eq. 44 in :mod:`femcheck.fe_device.contact_scales`).
"""
from __future__ import annotations

import numpy as np


def cable_stiffness(E_cable, diameter, length):
    """k_cable = E A / l (N/m), A = pi d^2 / 4."""
    return E_cable * np.pi * np.square(diameter) / 4.0 / length


def motor_stiffness_at_cable(G_shaft, shaft_diameter, shaft_length, capstan_radius):
    """k_motor = K_rotor / r^2 (N/m) with K_rotor = G (pi d^4 / 32) / L (N m/rad)."""
    K_rotor = G_shaft * np.pi * np.power(shaft_diameter, 4) / 32.0 / shaft_length
    return K_rotor / np.square(capstan_radius)


def actuation_compliance(c_act, e) -> np.ndarray:
    """6x6 compliance (frame U, any point on the rail) c_act [e e^T, 0; 0, 0]; c_act in m/N, e (3,) unit."""
    c_act = np.asarray(c_act, dtype=float)
    e = np.asarray(e, dtype=float)
    S = np.zeros(c_act.shape + (6, 6))
    S[..., :3, :3] = c_act[..., None, None] * np.outer(e, e)
    return S
