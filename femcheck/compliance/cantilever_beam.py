"""Cantilever beam tip compliance (docs/conventions.md §5; replaces seed 000 eq. 14 and the B_S_C matrix, eq. 17).

Clamped at local z = 0, tip at z = L; wrench and twist both at the tip, local frame, Euler-Bernoulli
with optional Timoshenko shear:

    S[0,0] = L^3/(3 E Iy) (+ L/(kappa G A))   S[0,4] = S[4,0] = +L^2/(2 E Iy)   S[4,4] = L/(E Iy)
    S[1,1] = L^3/(3 E Ix) (+ L/(kappa G A))   S[1,3] = S[3,1] = -L^2/(2 E Ix)   S[3,3] = L/(E Ix)
    S[2,2] = L/(E A)                           S[5,5] = L/(G Jt)

This is exactly the inverse of the 12/6/4 tip stiffness (12EI/L^3, -+6EI/L^2, 4EI/L, EA/L, GJ/L).
"""
from __future__ import annotations

import numpy as np

from femcheck.compliance.sections import Section


def cantilever_compliance(L, E, G, section: Section, shear: bool = False) -> np.ndarray:
    """Tip compliance (..., 6, 6) of a cantilever of length ``L`` (m), moduli ``E``, ``G`` (Pa).

    All arguments broadcast (e.g. L of shape (n, 6) for n poses x 6 chains).
    Units: translations m/N, rotations rad/(N m), couplings m/(N m) = rad/N.
    """
    L = np.asarray(L, dtype=float)
    E = np.asarray(E, dtype=float)
    G = np.asarray(G, dtype=float)
    shape = np.broadcast(L, E, G, section.A, section.Ix).shape
    S = np.zeros(shape + (6, 6))
    EIy, EIx = E * section.Iy, E * section.Ix
    lateral_shear = L / (section.shear_factor * G * section.A) if shear else 0.0
    S[..., 0, 0] = L**3 / (3.0 * EIy) + lateral_shear
    S[..., 0, 4] = S[..., 4, 0] = L**2 / (2.0 * EIy)
    S[..., 4, 4] = L / EIy
    S[..., 1, 1] = L**3 / (3.0 * EIx) + lateral_shear
    S[..., 1, 3] = S[..., 3, 1] = -(L**2) / (2.0 * EIx)
    S[..., 3, 3] = L / EIx
    S[..., 2, 2] = L / (E * section.A)
    S[..., 5, 5] = L / (G * section.Jt)
    return S
