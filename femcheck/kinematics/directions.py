"""Load directions: the one parser of a direction string ('+x', '-y', 'z') into a unit 3-vector.

Every caller (verify, sweep, device FE loads, CLI) resolves a direction here once and passes the
vector on; the spelling of a direction is part of the case/CLI contract (docs/conventions.md, base frame).
"""
from __future__ import annotations

import numpy as np

AXES = "xyz"


def direction_unit(direction: str, *, sign_required: bool = False) -> np.ndarray:
    """Unit vector (3,) of ``direction``: '+x' -> (1, 0, 0), '-z' -> (0, 0, -1), 'y' -> (0, 1, 0).

    Case-insensitive, surrounding blanks ignored; ``sign_required`` rejects the unsigned form.
    Raises ValueError naming the value and what was expected (callers wrap it into their own error type).
    """
    d = str(direction).strip().lower()
    axis = d.lstrip("+-")
    signs = d[: len(d) - len(axis)]
    if axis not in ("x", "y", "z") or len(axis) != 1 or len(signs) > 1 or (sign_required and not signs):
        expected = "one of +x, +y, +z, -x, -y, -z" if sign_required else "x, y or z with an optional sign"
        raise ValueError(f"direction {direction!r}; expected {expected}")
    v = np.zeros(3)
    v[AXES.index(axis)] = -1.0 if signs == "-" else 1.0
    return v
