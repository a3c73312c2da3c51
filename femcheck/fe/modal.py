"""Modal analysis: generalized eigenproblem K phi = omega^2 M phi (seed 004 eqs. 37, 44 use it with contact springs).

Shift-invert Lanczos (scipy ``eigsh``) around ``shift`` (rad/s)^2; free-free systems need a small
negative shift so that the factorization of K - shift M exists.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh


@dataclasses.dataclass(frozen=True)
class ModalResult:
    """``frequencies_Hz`` (m,) ascending; ``modes`` (ndof, m) mass-normalized (phi^T M phi = 1)."""

    frequencies_Hz: np.ndarray
    modes: np.ndarray


def natural_frequencies(K, M, n_modes: int, shift: float = 0.0) -> ModalResult:
    """Lowest ``n_modes`` natural frequencies above ``shift`` of the sparse pencil (K, M).

    K: (ndof, ndof) stiffness, N/m; M: (ndof, ndof) mass, kg (constrained DOFs already removed).
    """
    K = sp.csc_matrix(K)
    M = sp.csc_matrix(M)
    n_modes = int(min(n_modes, K.shape[0] - 2))
    vals, vecs = eigsh(K, k=n_modes, M=M, sigma=shift, which="LM")
    order = np.argsort(vals)
    vals, vecs = vals[order], vecs[:, order]
    omega = np.sqrt(np.clip(vals, 0.0, None))
    return ModalResult(frequencies_Hz=omega / (2.0 * np.pi), modes=vecs)


def contact_spring_stiffness(facet_basis, k_normal, k_tangential=0.0):
    """Contact-spring stiffness matrix K̃_C = ∫_Sc Nᵀ D_c N dS (seed 004 eq. 44), N/m.

    D_c = k_n n nᵀ + k_t (I − n nᵀ) is the contact property matrix per unit area (Pa/m = N/m³): normal
    and tangential contact stiffness of an interface spread over the facets of ``facet_basis`` (a
    ``skfem.FacetBasis`` of the vector element; n = outward normal). Added to K it gives the
    generalized eigenproblem (K + K̃_C) φ = ω² M φ of seed 004 eq. 37. For a total normal spring
    k (N/m) on a flat area A use k_normal = k / A. Returns csr (basis.N × basis.N).
    """
    from skfem import BilinearForm, asm
    from skfem.helpers import dot

    @BilinearForm
    def spring(u, v, w):
        n = w.n
        un, vn = dot(u, n), dot(v, n)
        return w.kn * un * vn + w.kt * (dot(u, v) - un * vn)

    shape = facet_basis.dx.shape
    kn = np.broadcast_to(np.asarray(k_normal, dtype=float), shape).copy()
    kt = np.broadcast_to(np.asarray(k_tangential, dtype=float), shape).copy()
    return sp.csr_matrix(asm(spring, facet_basis, kn=kn, kt=kt))


def bar_on_spring_roots(beta: float, n_modes: int) -> np.ndarray:
    """First ``n_modes`` roots λ_i l of tan(λ l) = β / (λ l) (seed 004 eqs. 29–30), dimensionless.

    Bar free at x = 0 and on a normal contact spring k_n at x = l, β = k_n l / (E A). Root i lies in
    ((i−1)π, (i−1)π + π/2). Natural frequencies follow from eq. 31: ω_i = λ_i sqrt(E/ρ).
    """
    from scipy.optimize import brentq

    if beta <= 0:
        raise ValueError(f"stiffness ratio beta = {beta}; expected > 0")
    g = lambda x: x * np.sin(x) - beta * np.cos(x)  # tan x = β/x without the poles
    eps = 1e-12
    return np.array([brentq(g, i * np.pi + eps, i * np.pi + np.pi / 2 - eps, xtol=1e-15) for i in range(n_modes)])
