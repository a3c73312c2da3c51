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
