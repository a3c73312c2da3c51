"""Normal contact by penalty with a Lagrange-multiplier estimate (seed 004 §3.1, eq. 1 augmented by ½ tᵀ[α]t).

At slave point i with gap g_i (m, > 0 open), multiplier estimate λ_i (Pa, ≥ 0, 0 for the plain penalty)
and penalty ε_i (Pa/m), the contact pressure (compression positive) is

    p_i = ⟨λ_i − ε_i g_i⟩₊                                   (Pa)

i.e. the Macaulay bracket of the augmented-Lagrangian trial pressure; the point is closed when
λ_i − ε_i g_i > 0. The internal force of the contact on the DOFs and its tangent are

    f_c = −B_nᵀ (w ∘ p)          (N, enters the residual r = f − K u − f_c)
    K_c = B_nᵀ diag(w ε [closed]) B_n   (N/m)

with w the integration weights (m²): the discrete form of −∫ p δg dA.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp


def trial_pressure(gap: np.ndarray, lam: np.ndarray, eps: np.ndarray) -> np.ndarray:
    """λ − ε g (Pa), (m,)."""
    return lam - eps * gap


def pressure(gap: np.ndarray, lam: np.ndarray, eps: np.ndarray) -> np.ndarray:
    """p = ⟨λ − ε g⟩₊ (Pa), (m,)."""
    return np.maximum(trial_pressure(gap, lam, eps), 0.0)


def normal_force(B_n: sp.csr_matrix, weights: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Nodal forces B_nᵀ (w p) (ndof,) N exerted by the pressure on the slave (+) and master (−) DOFs."""
    return B_n.T @ (weights * p)


def normal_stiffness(B_n: sp.csr_matrix, weights: np.ndarray, eps: np.ndarray, closed: np.ndarray) -> sp.csr_matrix:
    """K_c = B_nᵀ diag(w ε closed) B_n (ndof × ndof) N/m; closed (m,) bool."""
    d = weights * eps * closed
    return sp.csr_matrix(B_n.T @ sp.diags(d) @ B_n)
