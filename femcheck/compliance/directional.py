"""Stiffness along a direction from a TCP compliance (seed 000 §4.7): k_d = 1 / (d^T S_tt d), d a unit translation."""
from __future__ import annotations

import numpy as np


def directional_stiffness(S: np.ndarray, direction) -> np.ndarray:
    """(n,) stiffness, N/m, along the translation ``direction`` (3,) (normalized here) of compliances ``S`` (n, 6, 6)."""
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    return 1.0 / np.einsum("i,nij,j->n", d, S[:, :3, :3], d)
