"""The serial calibration bench's worlds: the hidden explanation is among the rivals weighed, and the posterior over
the rivals is a distribution (what the reliability tables and the ECE null of the 6-PSU bench assume)."""
from __future__ import annotations

import numpy as np
import pytest


@pytest.mark.parametrize("seed", [1, 4])
def test_a_world_weighs_its_hidden_explanation(seed):
    from femcheck.bench.serial_calibration import one_set
    s = one_set(seed)
    probs = np.array([p for _, p in s.explanations])
    # posterior over the rivals: sums to one (round-off), each in [0, 1]
    assert abs(probs.sum() - 1.0) < 1e-9 and probs.min() >= 0.0
    assert s.hidden in [ids for ids, _ in s.explanations]
    assert len(s.hidden) == len(s.rms_sigma) and all(0.5 <= r <= 8.0 for r in s.rms_sigma)
