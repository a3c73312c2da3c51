"""The mutable per-prediction arrays the diagnosis effects act on (:func:`femcheck.diagnose.model.predict_readings`)."""
from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass
class WorkingState:
    """Mutable per-prediction arrays the effects act on (m states).

    force (m, 3) N effective TCP force; scale (m, 6, 5) element compliance scales; c_rot rad/(N m);
    extra (m, 3) m displacement added to the model's; sensor (3, 3) maps true to read displacement.
    """

    force: np.ndarray
    scale: np.ndarray
    c_rot: float
    extra: np.ndarray
    sensor: np.ndarray
