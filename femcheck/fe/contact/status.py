"""Contact status of each slave integration point: open / stick / slide (seed 004 §3.2.1–3.2.3).

Codes (int8): ``OPEN = 0`` (gap open, no force, eq. 17), ``STICK = 1`` (closed, no relative tangential
motion, |F_S| < μ|F_n|, eq. 18), ``SLIDE = 2`` (closed, |F_S| = μ|F_n| along the slip, eq. 19).
"""
from __future__ import annotations

import numpy as np

OPEN, STICK, SLIDE = 0, 1, 2
NAMES = {OPEN: "open", STICK: "stick", SLIDE: "slide"}


def counts(status: np.ndarray) -> dict[str, int]:
    """{"open": n, "stick": n, "slide": n} for a status array (m,) int8."""
    return {name: int(np.count_nonzero(status == code)) for code, name in NAMES.items()}


def changed(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Indices of the points whose status differs between two status arrays (m,)."""
    return np.flatnonzero(np.asarray(a) != np.asarray(b))


def chattering(history: list[np.ndarray], min_flips: int = 2) -> np.ndarray:
    """Points whose status flipped at least ``min_flips`` times over the iterations in ``history``.

    history: list of status arrays (m,) in iteration order. Returns sorted point indices (k,).
    """
    if len(history) < 2:
        return np.zeros(0, dtype=np.int64)
    H = np.stack(history)
    flips = np.count_nonzero(H[1:] != H[:-1], axis=0)
    return np.flatnonzero(flips >= min_flips)
