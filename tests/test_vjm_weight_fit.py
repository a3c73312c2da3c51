"""Seed 001 eqs. 10-12 weight fit on the HISS case: restarts that converge, identifiability, intervals.

Virtual D/F experiments (``hiss_pipeline.virtual_experiment`` loads: 13 TPs x 5 random wrenches < 10 N, < 0.5 N m)
on the case's assumed layout. Residuals are weighted by the noise, 0.02 mm / 0.02 deg (L = 1/sigma^2).
``df_model`` reads eq. 10 as printed (quadratic, K' = W K W^T), the reading these figures were measured on;
``df_model_linear`` is the case's default reading (stiffness proportional to w).
"""
import numpy as np
import pytest

from femcheck.case import load_case
from femcheck.vjm import hiss_pipeline as hp
from femcheck.vjm.hiss_published import TABLE2
from femcheck.vjm.weight_fitting import fit_weights

TABLE2_DF = np.array(TABLE2["D/F"][0])
SIGMA = np.r_[[0.02e-3] * 3, [np.deg2rad(0.02)] * 3]
STRUCTURAL = {3, 7}                                   # W4, W8 (0-based)


@pytest.fixture(scope="module")
def hiss():
    return load_case("cases/hiss.toml")


@pytest.fixture(scope="module")
def df_model(hiss):
    d = hp.virtual_experiment(hiss, np.ones(11), setups=("D/F",), noise_mm=0, noise_deg=0, seed=1)
    return hp.model_for(hiss, d.point, d.wrench, reading="quadratic")


@pytest.fixture(scope="module")
def df_model_linear(hiss):
    d = hp.virtual_experiment(hiss, np.ones(11), setups=("D/F",), noise_mm=0, noise_deg=0, seed=1)
    return hp.model_for(hiss, d.point, d.wrench, reading="linear")


def _fit(model, measured, seed=0, restarts=12, profile=True):
    return fit_weights(model.predict, measured, model.n_weights, error_weight=1 / SIGMA ** 2, restarts=restarts,
                       seed=seed, jacobian=lambda w: model.predict_and_jacobian(w)[1], min_converged=3, profile=profile)


def _crlb_ratio(model, w):
    """Width ratio hi/lo of the 95 % interval of each weight from the Fisher information at the truth (inf: null)."""
    J = (model.predict_and_jacobian(w)[1] / SIGMA[None, :, None]).reshape(-1, len(w))
    ok = [k for k in range(len(w)) if k not in STRUCTURAL]
    sd = np.full(len(w), np.inf)
    sd[ok] = np.sqrt(np.diag(np.linalg.inv(J[:, ok].T @ J[:, ok])))
    return np.exp(2 * 1.96 * sd)


def test_exact_jacobian_matches_central_differences(df_model):
    w = np.exp(np.random.default_rng(3).uniform(np.log(0.05), np.log(2.0), 11))
    _, J = df_model.predict_and_jacobian(w)
    s, h = np.log(w), 1e-4
    fd = np.stack([(df_model.predict(np.exp(s + h * e)) - df_model.predict(np.exp(s - h * e))) / (2 * h)
                   for e in np.eye(11)], axis=-1)
    # central differences: truncation O(h^2) ~ 1e-8 plus round-off of cond(K_i) ~ 1e9 inverses over h
    np.testing.assert_allclose(J, fd, atol=1e-6 * np.abs(J).max())
    # W4 and W8 (link 2's in-plane shear and bending about the passive axis) move nothing: exactly zero
    assert np.abs(J[..., sorted(STRUCTURAL)]).max() < 1e-25 * np.abs(J).max()


def test_table2_df_truth_noise_free_recovers_nine_weights_and_flags_w4_w8(df_model):
    meas = df_model.predict(TABLE2_DF)
    fit = _fit(df_model, meas)
    flagged = set(np.flatnonzero(fit.unidentifiable))
    assert flagged == STRUCTURAL                               # issue 21 acceptance: exactly {W4, W8}
    assert all("structural" in fit.reasons[k] for k in STRUCTURAL)
    ok = [k for k in range(11) if k not in flagged]
    # issue 21 acceptance: 1e-4 (solver tolerance; observed ~1e-12)
    np.testing.assert_allclose(fit.weights[ok], TABLE2_DF[ok], rtol=1e-4)
    # several starts reach the same minimum (restarts that converge), not one lucky start
    assert len(fit.converged) >= 3


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_truths_noise_free_recover_and_flag_exactly_w4_w8(df_model, seed):
    """24 starts: some truths have a second minimum within 2e-5 sigma^2 of the exact fit (seed 4: W2 0.89
    against 0.40), which 12 starts all reached; noise-free data still single out the exact one."""
    rng = np.random.default_rng(100 + seed)
    w_true = np.exp(rng.uniform(np.log(0.02), np.log(1.5), 11))     # the span of Table 2's D/F weights
    fit = _fit(df_model, df_model.predict(w_true), seed=seed, restarts=24)
    assert set(np.flatnonzero(fit.unidentifiable)) == STRUCTURAL
    ok = [k for k in range(11) if k not in STRUCTURAL]
    np.testing.assert_allclose(fit.weights[ok], w_true[ok], rtol=1e-4)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(3, 11))
def test_more_random_truths_noise_free(df_model, seed):
    test_random_truths_noise_free_recover_and_flag_exactly_w4_w8(df_model, seed)


def test_restarts_are_deterministic(df_model):
    meas = df_model.predict(TABLE2_DF)
    a, b = _fit(df_model, meas, seed=4, restarts=4, profile=False), _fit(df_model, meas, seed=4, restarts=4, profile=False)
    np.testing.assert_array_equal(a.runs, b.runs)


def test_table2_df_truth_has_a_second_minimum_the_noise_cannot_rule_out(df_model):
    """Why W1, W3, W5 and W7 are not identified at 0.02 mm / 0.02 deg: on noise-free data a second minimum,
    with W7 twenty times smaller, W5 seven times larger and link 3 three times stiffer in bending (W11), misses
    the truth's 390 predictions by 0.14 sigma^2 in all (at most 1.5 um and 0.0012 deg on deflections up to 39 mm)."""
    from scipy.optimize import least_squares
    meas = df_model.predict(TABLE2_DF)
    r = lambda s: ((df_model.predict(np.exp(s)) - meas) / SIGMA).ravel()
    j = lambda s: (df_model.predict_and_jacobian(np.exp(s))[1] / SIGMA[None, :, None]).reshape(-1, 11)
    start = np.log([0.44, 0.038, 2.2, 1.0, 5.1, 0.15, 0.05, 1.0, 0.076, 0.02, 0.39])   # found by the restarts
    sol = least_squares(r, start, jac=j, method="trf", xtol=1e-12, ftol=1e-14, gtol=1e-14)
    w2 = np.exp(sol.x)
    assert 2 * sol.cost < 1.0                               # chi^2 distance to the truth's predictions, < 1
    assert w2[6] < 0.1 * TABLE2_DF[6]                        # W7 0.05 against 0.977
    assert w2[4] > 2 * TABLE2_DF[4] and w2[10] > 2 * TABLE2_DF[10]   # W5 6.3 against 0.866, W11 0.39 against 0.125


def _check_flags(fit, crlb, w_true):
    """Flags against the Fisher information at the truth: structural and barely seen weights (95 % Cramer-Rao
    interval wider than a factor 100) are flagged; well seen ones (within 10 %) are not, and their intervals
    cover the truth (widened by their own width once, ~4 sd, so that the test is not a 95 % coin). Between
    the two, a flag depends on the noise draw and is not asserted."""
    flagged = fit.unidentifiable
    assert STRUCTURAL <= set(np.flatnonzero(flagged))
    assert flagged[np.isfinite(crlb) & (crlb > 100)].all()
    assert not flagged[crlb < 1.1].any()
    ok = ~flagged
    lo, hi = fit.ci_low[ok], fit.ci_high[ok]
    assert np.all(np.isfinite(hi)) and np.all(lo > 0)          # intervals are reported
    wid = np.sqrt(hi / lo)
    assert np.all((w_true[ok] >= lo / wid) & (w_true[ok] <= hi * wid))


@pytest.mark.slow   # 15 s (CI budget); the noise-free random truths stay in the default suite
def test_table2_df_truth_with_noise_flags_more_than_w4_w8(df_model):
    """Issue 21 expected only {W4, W8} flagged at 0.02 mm / 0.02 deg; the physics says otherwise (finding):
    at the truth, the 95 % Cramer-Rao intervals of W1, W3, W5, W7 span factors 77, 17, 3.7e3 and 2e5 (the
    other five: at most 1.07), and a second minimum (previous test) fits as well. This noise draw flags all
    four; other draws may leave W1 or W3 unflagged (the slow variants check only the rule of _check_flags)."""
    crlb = _crlb_ratio(df_model, TABLE2_DF)
    assert np.all(crlb[[0, 2, 4, 6]] > 7) and np.all(crlb[[1, 5, 8, 9, 10]] < 1.1)
    rng = np.random.default_rng(200)
    meas = df_model.predict(TABLE2_DF) + rng.normal(size=(65, 6)) * SIGMA
    fit = _fit(df_model, meas)
    assert set(np.flatnonzero(fit.unidentifiable)) == {0, 2, 3, 4, 6, 7}
    _check_flags(fit, crlb, TABLE2_DF)


@pytest.mark.slow
@pytest.mark.parametrize("noise_seed", [1, 2, 3])
def test_table2_df_truth_with_noise_more_seeds(df_model, noise_seed):
    rng = np.random.default_rng(200 + noise_seed)
    meas = df_model.predict(TABLE2_DF) + rng.normal(size=(65, 6)) * SIGMA
    _check_flags(_fit(df_model, meas), _crlb_ratio(df_model, TABLE2_DF), TABLE2_DF)


def _random_truth_with_noise(df_model, seed):
    rng = np.random.default_rng(300 + seed)
    w_true = np.exp(rng.uniform(np.log(0.02), np.log(1.5), 11))
    meas = df_model.predict(w_true) + rng.normal(size=(65, 6)) * SIGMA
    _check_flags(_fit(df_model, meas, seed=seed), _crlb_ratio(df_model, w_true), w_true)


def test_random_truth_with_noise(df_model):
    _random_truth_with_noise(df_model, 3)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2, 4, 5, 6])
def test_more_random_truths_with_noise(df_model, seed):
    _random_truth_with_noise(df_model, seed)
