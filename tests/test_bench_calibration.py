"""The reliability table of ``femcheck.bench.calibration`` on outcomes whose calibration is known."""
import numpy as np
import pytest

import femcheck
from femcheck.bench.calibration import reliability, shrunk_truth
from femcheck.diagnose import AnalyticalChainModel
from femcheck.diagnose.effects import get_effect


def test_calibrated_outcomes_give_a_small_calibration_error():
    rng = np.random.default_rng(0)
    p = rng.uniform(0, 1, 20000)
    r = reliability(p, rng.uniform(0, 1, p.size) < p)
    # a calibrated forecaster: each bin's observed frequency within 4 binomial standard errors of its mean
    for b in r["bins"]:
        assert abs(b["observed"] - b["mean_predicted"]) < 4 * b["observed_se"] + 1e-9
    assert r["ece"] < 0.02 and r["n"] == p.size
    # Brier score of a calibrated forecaster with p ~ U(0, 1): E[p (1 - p)] = 1/6
    assert r["brier"] == pytest.approx(1 / 6, abs=0.01)


def test_overconfident_outcomes_are_flagged():
    p = np.full(1000, 0.95)
    r = reliability(p, np.arange(1000) < 500)          # right half the time
    top = r["bins"][-1]
    assert top["n"] == 1000 and top["observed"] == pytest.approx(0.5) and r["ece"] == pytest.approx(0.45)


def test_shrunk_truth_moves_towards_the_neutral_value():
    case = femcheck.load_case("cases/haptic_6psu.toml")
    model = AnalyticalChainModel(case)
    eff = get_effect("actuation_compliance")
    full = shrunk_truth(eff, model, np.random.default_rng(3), case, 1.0)["scale"]
    half = shrunk_truth(eff, model, np.random.default_rng(3), case, 0.5)["scale"]
    assert half == pytest.approx(1.0 + 0.5 * (full - 1.0))     # linear parameter, neutral 1 in the detailed model
    eff = get_effect("link_modulus")                          # log parameter: halfway in log10
    full = shrunk_truth(eff, model, np.random.default_rng(4), case, 1.0)["E_factor"]
    half = shrunk_truth(eff, model, np.random.default_rng(4), case, 0.5)["E_factor"]
    assert half == pytest.approx(np.sqrt(full))


def test_a_set_drawn_from_the_prior_is_weighed_by_both_evidences():
    """``--truth prior``: the hidden explanation comes from the size prior and its parameters from the stated prior;
    both evidence approximations weigh the same fits, each a probability distribution over the same rivals."""
    from femcheck.bench.calibration import one_set
    s = one_set(3, truth="prior")
    assert set(s.by_method) == {"laplace", "bic"} and len(s.hidden) <= 2
    for m, expl in s.by_method.items():
        assert sum(p for _, p in expl) == pytest.approx(1.0, abs=1e-12)      # normalized posterior
        assert {ids for ids, _ in expl} == {ids for ids, _ in s.by_method["bic"]}
    # both likelihoods weigh the same fits; without a scatter estimate of sigma (sigma_dof = 0) they agree exactly
    assert set(s.by_likelihood) == {"gauss", "student"} and s.by_likelihood["gauss"] == s.by_method
    for m, expl in s.by_likelihood["student"].items():
        assert sum(p for _, p in expl) == pytest.approx(1.0, abs=1e-12)
        if s.sigma_dof == 0:
            assert expl == s.by_likelihood["gauss"][m]
    # the generator's truth lies within each parameter's bounds
    from femcheck.diagnose.effects import get_effect
    for eid, params in s.truth:
        bounds = {p.name: (p.lower, p.upper) for p in get_effect(eid).params}
        assert all(bounds[n][0] <= v <= bounds[n][1] for n, v in params)


def test_cause_error_is_split_by_sets_that_hide_a_located_effect():
    """``located_split``: the cause table of the sets hiding an ``*_in_legs`` effect and of the others, flat keys. Two
    fabricated sets: a located truth given 0.0 (off by 1 on one of its two causes) and a non-located truth given
    exactly (error 0), so the split ECEs are known exactly."""
    from femcheck.bench.calibration import GeneratedSet, located_split
    mk = lambda seed, hidden, expl: GeneratedSet(seed=seed, hidden=hidden, shrink=float("nan"), points=(), directions=(),
                                                 explanations=expl, causes={"guideway_in_legs": 0.0, "clearance": 0.0},
                                                 seconds=0.0)
    sets = [mk(0, ("guideway_in_legs",), ((("clearance",), 0.0), ((), 1.0))),   # none given 1: the located one missed
            mk(1, ("clearance",), ((("clearance",), 1.0),))]
    out = located_split(sets, lambda s: s.explanations)
    assert out["n_sets_located_sets"] == 1 and out["n_sets_other_sets"] == 1
    # located set: causes (guideway 0 -> hidden, clearance 0 -> not): |1 - 0| / 2 = 0.5; other set: exact
    assert out["cause_ece_located_sets"] == pytest.approx(0.5) and out["cause_ece_other_sets"] == pytest.approx(0.0)


def test_cause_error_is_split_by_the_kind_of_cause_with_a_calibrated_null():
    """``located_split`` by cause kind over all sets, and the ECE a calibrated predictor would show
    (:func:`ece_null`). Fabricated sets with known answers: a located cause given 0.0 that was hidden (error 1) and a
    non-located one given exactly; then predictions drawn calibrated by construction (outcomes Bernoulli(p)) must not
    be flagged, and the same predictions with their outcomes flipped must be."""
    from femcheck.bench.calibration import GeneratedSet, ece_null, located_split, reliability
    mk = lambda seed, hidden, expl, causes: GeneratedSet(seed=seed, hidden=hidden, shrink=float("nan"), points=(),
                                                         directions=(), explanations=expl, causes=causes, seconds=0.0)
    sets = [mk(0, ("guideway_in_legs",), ((("clearance",), 0.0), ((), 1.0)),
               {"guideway_in_legs": 0.0, "clearance": 0.0}),
            mk(1, ("clearance",), ((("clearance",), 1.0),), {"guideway_in_legs": 0.0, "clearance": 0.0})]
    out = located_split(sets, lambda s: s.explanations)
    # located causes: guideway 0 (hidden) and guideway 0 (not): |0.5 - 0| = 0.5; other causes: 0 and 1, both right
    assert out["cause_ece_located_causes"] == pytest.approx(0.5) and out["cause_ece_other_causes"] == pytest.approx(0.0)
    rng = np.random.default_rng(5)
    p = rng.beta(0.3, 0.9, size=400)
    y = rng.uniform(size=p.size) < p
    null = ece_null(p, n_draws=400, seed=1)
    # calibrated by construction: its ECE lies inside the null (a 1-in-200 miss allowed: 0.995 quantile)
    assert reliability(p, y)["ece"] <= np.quantile(null, 0.995)
    # the outcomes of 1 - p: grossly miscalibrated, far beyond the null's range
    assert reliability(p, ~y)["ece"] > np.quantile(null, 0.999)
