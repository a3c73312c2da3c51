"""The generic verdict/evidence machinery: closed forms of the chi^2 and F tails,
BIC weights, the verdict rules and the ambiguity sentence."""
import numpy as np
import pytest

from femcheck.diagnose.evidence import Explanation, bic, goodness, posterior, weigh


def test_chi2_tail_closed_form_for_two_dof():
    # chi^2 with 2 dof is exponential: P(X >= c) = exp(-c / 2)
    for c in (0.5, 3.0, 12.0):
        assert goodness(c, 2)[1] == pytest.approx(np.exp(-c / 2), rel=1e-12)   # scipy special-function accuracy


def test_f_test_tends_to_the_chi2_test_when_sigma_is_well_known():
    c, dof = 130.0, 100
    p_chi2 = goodness(c, dof)[1]
    assert goodness(c, dof, sigma_dof=10 ** 7)[1] == pytest.approx(p_chi2, rel=1e-3)   # F(d, inf) = chi2_d / d
    # an estimated sigma is itself uncertain: the same misfit is less significant
    assert goodness(c, dof, sigma_dof=50)[1] > 2 * p_chi2


def test_bic_weights_are_exponentials_of_half_the_bic_difference():
    n = 100
    a = Explanation(("a",), 50.0, 1)
    b = Explanation(("b",), 50.0 + 2 * np.log(3.0), 1)   # Delta BIC = 2 ln 3 -> posterior ratio 3
    none = Explanation((), 500.0, 0)
    p = posterior([a, b, none], n)
    assert p[0] / p[1] == pytest.approx(3.0, rel=1e-12)   # float rounding
    assert p.sum() == pytest.approx(1.0, rel=1e-12)
    # each parameter costs ln N
    assert bic(10.0, 2, n) - bic(10.0, 0, n) == pytest.approx(2 * np.log(n), rel=1e-12)


def test_verdicts():
    n = 400
    none_fits = weigh([Explanation((), 400.0, 0), Explanation(("a",), 399.0, 1)], n)
    assert none_fits.verdict == "none" and none_fits.best.ids == ()
    explained = weigh([Explanation((), 4000.0, 0), Explanation(("a",), 401.0, 1)], n)
    assert explained.verdict == "explained" and explained.best.ids == ("a",)
    assert explained.unexplained_fraction == 0.0 and none_fits.unexplained_fraction == 0.0   # within noise
    partial = weigh([Explanation((), 4000.0, 0), Explanation(("a",), 1200.0, 1)], n)
    assert partial.verdict == "unexplained" and partial.best.ids == ("a",)
    # excess over noise left: (1200 - 399) / (4000 - 400)
    assert partial.unexplained_fraction == pytest.approx(801 / 3600, rel=1e-12)
    nothing = weigh([Explanation((), 1500.0, 0), Explanation(("a",), 1499.0, 1)], n)
    assert nothing.verdict == "unexplained" and nothing.best.ids == ()


def test_ambiguity_is_reported_against_a_non_nested_rival():
    n = 400
    rivals = [Explanation((), 4000.0, 0), Explanation(("actuation_compliance",), 400.0, 1),
              Explanation(("leg_softening",), 400.5, 1), Explanation(("actuation_compliance", "link_modulus"), 399.9, 2)]
    w = weigh(rivals, n)
    assert w.ambiguous and "actuation_compliance" in w.ambiguity and "leg_softening" in w.ambiguity
    assert "not separable" in w.ambiguity
    clear = weigh([rivals[0], rivals[1], Explanation(("leg_softening",), 440.0, 1)], n)
    assert not clear.ambiguous and clear.ambiguity == ""


def test_chosen_explanation_is_named_first():
    rivals = [Explanation((), 4000.0, 0), Explanation(("a",), 400.0, 1), Explanation(("b",), 410.0, 1)]
    w = weigh(rivals, 400, chosen=("b",))
    assert w.best.ids == ("b",) and sum(w.probability) == pytest.approx(1.0)
    with pytest.raises(ValueError):
        weigh(rivals[1:], 400)


def test_size_prior_gives_each_explanation_size_equal_mass():
    """none, the singles and the pairs get a third of the prior each, shared within the size (Scott & Berger 2010);
    with equal evidence the posterior is that prior (exact: no data term differs)."""
    from femcheck.diagnose.evidence import Explanation, posterior, size_prior
    ex = [Explanation((), 10.0, 0)] + [Explanation((a,), 10.0, 0) for a in "abc"] + \
         [Explanation((a, b), 10.0, 0) for a, b in ("ab", "ac", "bc")]
    pi = size_prior(ex)
    assert np.isclose(pi.sum(), 1.0) and np.isclose(pi[0], 1 / 3) and np.allclose(pi[1:], 1 / 9)
    assert np.allclose(posterior(ex, 100), pi)
    ex10 = [Explanation((), 0.0, 0)] + [Explanation((str(i),), 0.0, 0) for i in range(10)] + \
           [Explanation((str(i), str(j)), 0.0, 0) for i in range(10) for j in range(i + 1, 10)]
    p = posterior(ex10, 100)
    assert np.isclose(p[11:].sum(), 1 / 3)     # 45 pairs: a third, not 45/56 of the mass


def _linear_problem(n, k, rng, sigma=None):
    X = rng.normal(size=(n, k))
    sig = rng.uniform(0.5, 2.0, n) if sigma is None else np.full(n, sigma)
    mu, sd = rng.normal(size=k), rng.uniform(0.3, 3.0, k)
    beta = mu + sd * rng.normal(size=k)
    y = X @ beta + sig * rng.normal(size=n)
    J = X / sig[:, None]
    x_ml, *_ = np.linalg.lstsq(J, y / sig, rcond=None)
    chi2 = float(np.sum((y / sig - J @ x_ml) ** 2))
    return X, y, sig, mu, sd, J, x_ml, chi2


def test_laplace_evidence_is_exact_for_a_linear_gaussian_model():
    """y = X b + e, e ~ N(0, diag sigma^2), b ~ N(mu, diag w^2): the marginal likelihood is N(y; X mu, diag sigma^2 +
    X W^2 X^T) in closed form, and the Laplace approximation is exact (the log posterior is quadratic)."""
    from scipy.stats import multivariate_normal
    from femcheck.diagnose.evidence import laplace_score
    rng = np.random.default_rng(11)
    for n, k in ((30, 3), (12, 1), (50, 5)):
        X, y, sig, mu, sd, J, x_ml, chi2 = _linear_problem(n, k, rng)
        exact = -2.0 * multivariate_normal(X @ mu, np.diag(sig ** 2) + X @ np.diag(sd ** 2) @ X.T).logpdf(y)
        # laplace_score drops the likelihood constant N ln 2 pi + 2 sum ln sigma shared by every explanation
        approx = laplace_score(chi2, J, x_ml, mu, sd) + n * np.log(2 * np.pi) + 2 * np.sum(np.log(sig))
        assert approx == pytest.approx(exact, rel=1e-10)   # float rounding of two equivalent closed forms


def test_laplace_evidence_tends_to_bic_plus_a_constant():
    """Schwarz (1978): ln Z = ln L_max - (k/2) ln N + O(1). For N iid rows with per-row information I1 the Laplace
    Occam term -2 ln Z - chi2_min tends to k ln N + ln det(W I1 W) + d^T W^-2 d (d = x_ML - mu): BIC up to a constant."""
    from femcheck.diagnose.evidence import laplace_score
    rng = np.random.default_rng(5)
    k = 2
    mu, sd = np.array([0.2, -0.1]), np.array([1.0, 0.5])
    base = rng.normal(size=(100, k))
    gaps = []
    for reps in (10, 100, 10000):
        J = np.tile(base, (reps, 1))                       # N = 100 reps rows, the same per-row information
        n = J.shape[0]
        x = np.array([0.5, 0.3])                           # the ML point (the Occam term does not need the data)
        occam = laplace_score(0.0, J, x, mu, sd)
        I1 = base.T @ base / 100
        limit = np.linalg.slogdet(np.diag(sd) @ I1 @ np.diag(sd))[1] + np.sum(((x - mu) / sd) ** 2)
        gaps.append(occam - k * np.log(n) - limit)
    # the remainder falls like 1/N: below 1e-3 at N = 1e6 (the O(1) term of BIC is this constant)
    assert abs(gaps[-1]) < 1e-3 and abs(gaps[0]) > abs(gaps[1]) > abs(gaps[2])


def test_truncated_prior_mass_and_draws():
    """A parameter whose neutral value is its bound has a half-normal prior: mass 1/2 inside, draws >= the bound
    with mean w sqrt(2/pi) (scaled coordinates)."""
    import femcheck
    from femcheck.diagnose import AnalyticalChainModel
    from femcheck.diagnose.effects import get_effect
    from femcheck.diagnose.prior import draw_values, effect_prior
    model = AnalyticalChainModel(femcheck.load_case("cases/haptic_6psu.toml"))
    eff = get_effect("friction_hysteresis")
    q = effect_prior(eff, model)
    # the upper bound (60 N) lies 6 prior widths out: the mass above it is 1e-9
    assert q.mass[0] == pytest.approx(0.5, rel=1e-8) and q.mu[0] == 0.0
    rng = np.random.default_rng(0)
    x = np.array([draw_values(eff, model, rng)["friction_N"] for _ in range(4000)]) / eff.params[0].typical
    assert x.min() >= 0.0
    # standard error of the mean of 4000 half-normal draws: w sqrt(1 - 2/pi) / sqrt(4000) = 0.019 w; 4 se
    assert x.mean() == pytest.approx(q.sd[0] * np.sqrt(2 / np.pi), abs=4 * 0.019 * q.sd[0])
    # a located effect draws its legs first: 1..6 legs (all six is a placement too), each within the bounds
    from femcheck.diagnose.prior import draw_truth
    eid, vals = draw_truth(get_effect("actuation_in_legs"), model, rng)
    assert eid == "actuation_in_legs" and 1 <= len(vals) <= 6 and all(0.0 <= v <= 30.0 for v in vals.values())


@pytest.fixture(scope="module")
def sparse_diagnosis():
    from tests.conftest import sparse_actuation_readings
    return sparse_actuation_readings()


def test_diagnosis_weighs_by_laplace_on_request(sparse_diagnosis):
    from femcheck.diagnose import diagnose
    from femcheck.diagnose.evidence import posterior
    model, readings = sparse_diagnosis
    pool = ["actuation_compliance", "joint_contact_compliance", "link_modulus"]
    d = diagnose(model, readings, candidates=pool, with_baseline=False, evidence_method="laplace")
    w = d.weighing
    assert w.method == "laplace" and d.as_json()["evidence"].startswith("Laplace")
    assert all(e.occam is not None for e in w.explanations if e.n_params)
    # the weighing's probabilities are the Laplace posterior of its explanations (same fits, exact re-evaluation)
    assert np.allclose(w.probability, posterior(w.explanations, w.n_data, "laplace"), rtol=1e-12, atol=0)
    # a one-parameter Occam term: ln(1 + w^2 J^T J) + z^2 + 2 ln mass, positive and below BIC's ln N + 10 here
    single = next(e for e in w.explanations if e.ids == ("actuation_compliance",))
    assert 0.0 < single.occam < np.log(w.n_data) + 10.0
    assert d.causes[0].id == "actuation_compliance"      # a 1.5x softer drive, the truth, is named either way
    with pytest.raises(ValueError, match="evidence_method"):
        diagnose(model, readings, candidates=pool, with_baseline=False, evidence_method="aic")


def test_gauss_newton_floor_and_a_stopped_fit(sparse_diagnosis):
    from femcheck.diagnose.effects import get_effect
    from femcheck.diagnose.fitting import early_stop_rules, fit_effects, gauss_newton_floor
    rng = np.random.default_rng(2)
    X, r = rng.normal(size=(40, 3)), rng.normal(size=40)
    b, *_ = np.linalg.lstsq(X, r, rcond=None)
    # linear residual: the floor is the least-squares minimum
    assert gauss_newton_floor(r, X) == pytest.approx(float(np.sum((r - X @ b) ** 2)), rel=1e-12)
    model, readings = sparse_diagnosis
    effs = [get_effect("clearance"), get_effect("link_modulus")]
    full = fit_effects(model, readings, effs, max_nfev=100)
    with early_stop_rules(rho_tol=np.inf):         # every floor believed: every probe judged hopeless
        stopped = fit_effects(model, readings, effs, max_nfev=100, stop_above=-1.0)
    # a stopped fit reports the chi^2 it reached: never below the converged one (less than fit tolerance 1e-6)
    assert stopped.stopped_early and not full.stopped_early
    assert stopped.chi2 >= full.chi2 * (1 - 1e-6)
