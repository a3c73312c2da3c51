"""Universal joint: Hertz line contact of a pin in its bore plus simply supported pin bending
(seed 000 eqs. 36-42; docs/conventions.md §5 "Universal joint").

    K_UC = pi l E* / 2                       line-contact stiffness (the paper's pi l E'/4, E' = 2E*)
    K_UB = 48 E_pin (pi r^4 / 4) / L_u^3     centre-loaded simply supported pin of span L_u
    S_uj^L = diag(1/K_UC, 1/K_UC, 1/K_UC + 1/K_UB, 0, 0, 0)   in the link frame B_i at C_i

Contact and bending carry the same force along the link axis, so they are in series (the paper
has K_uz = K_UB alone; see docs/conventions.md [DEV]).

:func:`line_contact_stiffness` and :func:`pin_bending_stiffness` are THE implementations of the U joint's laws:
:func:`femcheck.chain.device_parameters` and :func:`femcheck.parallel.device.device_from_case` read them from this
module when they run (the compiled kernels receive c_uc, c_ub as parameters).
"""
from __future__ import annotations

import numpy as np


def line_contact_stiffness(contact_length, E_star):
    """K_UC = pi l E* / 2 (N/m) for a line contact of length ``contact_length`` (m)."""
    return np.pi * np.asarray(contact_length, dtype=float) * E_star / 2.0


def pin_bending_stiffness(E_pin, pin_radius, span):
    """K_UB = 48 E I / L^3 (N/m), I = pi r^4 / 4: a centre-loaded, simply supported pin."""
    I = np.pi * np.power(pin_radius, 4) / 4.0
    return 48.0 * E_pin * I / np.power(span, 3)


def universal_joint_compliance(K_UC, K_UB) -> np.ndarray:
    """Local 6x6 compliance in the link frame: diag(1/K_UC, 1/K_UC, 1/K_UC + 1/K_UB, 0, 0, 0)."""
    K_UC, K_UB = np.broadcast_arrays(np.asarray(K_UC, float), np.asarray(K_UB, float))
    S = np.zeros(K_UC.shape + (6, 6))
    S[..., 0, 0] = S[..., 1, 1] = 1.0 / K_UC
    S[..., 2, 2] = 1.0 / K_UC + 1.0 / K_UB
    return S
