"""Cantilever beam tip compliance (docs/conventions.md §5; replaces seed 000 eq. 14 and the B_S_C matrix, eq. 17).

Clamped at local z = 0, tip at z = L; wrench and twist both at the tip, local frame, Euler-Bernoulli
with optional Timoshenko shear:

    S[0,0] = L^3/(3 E Iy) (+ L/(kappa G A))   S[0,4] = S[4,0] = +L^2/(2 E Iy)   S[4,4] = L/(E Iy)
    S[1,1] = L^3/(3 E Ix) (+ L/(kappa G A))   S[1,3] = S[3,1] = -L^2/(2 E Ix)   S[3,3] = L/(E Ix)
    S[2,2] = L/(E A)                           S[5,5] = L/(G Jt)

This is exactly the inverse of the 12/6/4 tip stiffness (12EI/L^3, -+6EI/L^2, 4EI/L, EA/L, GJ/L).

:func:`cantilever_terms` is THE implementation of the cantilever law: :func:`cantilever_compliance` places its
eight distinct entries in the 6 x 6 matrix, and the compiled chain kernel
(:mod:`femcheck.parallel.chain_kernel`) calls the function this module holds when it runs, compiled by
:func:`femcheck.compliance.kernel_laws.kernel_laws` (a numba-compatible leaf: scalars or numpy arrays).
"""
from __future__ import annotations

import numpy as np
from numba.extending import register_jitable

from femcheck.compliance.sections import Section


@register_jitable
def cantilever_terms(L, E, G, A, Ix, Iy, Jt, shear_factor, shear):
    """The eight distinct tip-compliance entries (S00, S04, S44, S11, S13, S33, S22, S55) of a cantilever of length
    ``L`` (m), moduli ``E``, ``G`` (Pa), section ``A``, ``Ix``, ``Iy``, ``Jt``, ``shear_factor`` (module doc's
    table; ``shear``: add the Timoshenko shear term). Scalars or arrays (broadcast), also callable from
    numba-compiled code."""
    EIy = E * Iy
    EIx = E * Ix
    lateral_shear = L / (shear_factor * G * A) if shear else 0.0
    return (L**3 / (3.0 * EIy) + lateral_shear, L**2 / (2.0 * EIy), L / EIy,
            L**3 / (3.0 * EIx) + lateral_shear, -(L**2) / (2.0 * EIx), L / EIx, L / (E * A), L / (G * Jt))


def cantilever_compliance(L, E, G, section: Section, shear: bool = False) -> np.ndarray:
    """Tip compliance (..., 6, 6) of a cantilever of length ``L`` (m), moduli ``E``, ``G`` (Pa): the entries of
    :func:`cantilever_terms`, looked up in this module when called.

    All arguments broadcast (e.g. L of shape (n, 6) for n poses x 6 chains).
    Units: translations m/N, rotations rad/(N m), couplings m/(N m) = rad/N.
    """
    L = np.asarray(L, dtype=float)
    E = np.asarray(E, dtype=float)
    G = np.asarray(G, dtype=float)
    shape = np.broadcast(L, E, G, section.A, section.Ix).shape
    S = np.zeros(shape + (6, 6))
    s00, s04, s44, s11, s13, s33, s22, s55 = cantilever_terms(L, E, G, section.A, section.Ix, section.Iy, section.Jt,
                                                              section.shear_factor, bool(shear))
    S[..., 0, 0] = s00
    S[..., 0, 4] = S[..., 4, 0] = s04
    S[..., 4, 4] = s44
    S[..., 1, 1] = s11
    S[..., 1, 3] = S[..., 3, 1] = s13
    S[..., 3, 3] = s33
    S[..., 2, 2] = s22
    S[..., 5, 5] = s55
    return S
