"""Preload law k = c P^m fitted in log space."""
import numpy as np
import pytest

from femcheck.contact_id.bar_on_spring import ContactIdError
from femcheck.contact_id.preload_law import fit_power_law


def test_exact_data_recovers_c_and_m():
    P = np.array([100.0, 200, 400, 800, 1600])
    law = fit_power_law(P, 3.0e6 * P**0.62)
    # noise-free data: only round-off in the log fit
    assert abs(law.c / 3.0e6 - 1) < 1e-10 and abs(law.m - 0.62) < 1e-12


def test_noisy_data_within_uncertainty_and_band_coverage():
    rng = np.random.default_rng(4)
    P = np.geomspace(50, 5000, 12)
    sigma = 0.05
    hits_m, hits_band, trials = 0, 0, 400
    for _ in range(trials):
        k = 1e6 * P**0.8 * np.exp(rng.normal(0, sigma, P.size))
        law = fit_power_law(P, k, sigma_ln_k=np.full(P.size, sigma))
        hits_m += abs(law.m - 0.8) < 1.96 * law.sigma_m
        lo, hi = law.band(1000.0)
        hits_band += lo <= 1e6 * 1000.0**0.8 <= hi
    # 95 % intervals: binomial 1-sigma on 400 trials is 1.1 %, so accept 90-99 %
    assert 0.90 < hits_m / trials < 0.99
    assert 0.90 < hits_band / trials < 0.99


def test_bad_input():
    with pytest.raises(ContactIdError, match="preload"):
        fit_power_law([100, -1], [1e6, 2e6])
    with pytest.raises(ContactIdError, match="2 distinct"):
        fit_power_law([100, 100], [1e6, 2e6])
    with pytest.raises(ContactIdError, match="one preload per"):
        fit_power_law([100, 200, 300], [1e6, 2e6])
