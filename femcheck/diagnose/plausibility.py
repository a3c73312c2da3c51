"""Are the readings on the scale the case predicts? A check before a diagnosis.

A diagnosis fits factors to whatever it is given: readings 1000x too large (micrometres written in a millimetre
column) would still get a verdict and a table of causes. The check compares the median magnitude of the measured
deflections with the median the case's model predicts for the same loads and poses. A ratio beyond
:data:`SCALE_LIMIT` (or below its inverse) is far outside any stiffness error a cause of the vocabulary can make (a
factor of 10 in every element at once); it is named with the unit mix-up whose factor lies nearest on a log scale.
"""
from __future__ import annotations

import numpy as np

#: measured / predicted median deflection beyond this factor (either way) is a scale error, not a finding
SCALE_LIMIT = 10.0

#: (measured / predicted factor, what it looks like) for the column unit mm
UNIT_SLIPS = ((1e3, "readings look like µm written as mm"),
              (1e-3, "readings look like m written as mm"),
              (1.0 / 25.4, "readings look like inches written as mm"),
              (1e3 / 25.4, "readings look like thousandths of an inch written as mm"),
              (1e6, "readings look like nm written as mm"))


def likely_unit(ratio: float) -> str:
    """The unit mix-up of :data:`UNIT_SLIPS` nearest to ``ratio`` (within a factor of 2 on a log scale), else a
    plain statement of the factor."""
    lr = np.log10(ratio)
    factor, text = min(UNIT_SLIPS, key=lambda ft: abs(np.log10(ft[0]) - lr))
    if abs(np.log10(factor) - lr) < np.log10(2.0):
        return text
    return f"readings are {ratio:.3g}x the model's; check the unit of the displacement columns"


def scale_check(measured: np.ndarray, predicted: np.ndarray, limit: float = SCALE_LIMIT) -> tuple[float, str | None]:
    """(median |measured| / median |predicted|, the problem or None). ``measured``, ``predicted``: deflections of the
    same loaded readings (any shape, m). Readings that are all zero, or a model that predicts none, give (nan, None):
    nothing to compare."""
    m = float(np.median(np.abs(np.asarray(measured, float))))
    p = float(np.median(np.abs(np.asarray(predicted, float))))
    if not p > 0:
        return float("nan"), None
    if m == 0.0:   # rounded away: a value in m written in the mm column keeps no digit of a sub-mm deflection
        return 0.0, (f"median measured deflection is 0 where the case predicts {p * 1e3:.4g} mm: readings look like "
                     f"m written as mm (rounded to zero), or the dials were not read (--force diagnoses them anyway)")
    ratio = m / p
    if ratio > limit or ratio < 1.0 / limit:
        return ratio, (f"median measured deflection {m * 1e3:.4g} mm is {ratio:.3g}x the {p * 1e3:.4g} mm the case "
                       f"predicts: {likely_unit(ratio)} (--force diagnoses them anyway)")
    return ratio, None
