"""sigma's own uncertainty in the evidence: the Student-t likelihood that integrates sigma^2 out of
its scatter estimate with nu dof, -2 ln L = (N + nu) ln(1 + chi^2 / nu) + const."""
import numpy as np
import pytest
from scipy import integrate, special, stats

from femcheck.diagnose import evidence
from femcheck.diagnose.evidence import Explanation, laplace_score, posterior, student_curvature, student_term


@pytest.mark.parametrize("n, nu", [(1, 1), (6, 3), (27, 48)])
def test_student_term_is_the_multivariate_t_density(n, nu):
    """-2 ln of scipy's multivariate t (nu dof, scale s^2 I) at residual r is the term plus its stated constant."""
    rng = np.random.default_rng(n + nu)
    s = 2.5e-6
    for _ in range(5):
        r = rng.normal(0.0, 3.0 * s, n)
        chi2 = float(np.sum((r / s) ** 2))
        ref = -2.0 * stats.multivariate_t(loc=np.zeros(n), shape=s ** 2 * np.eye(n), df=nu).logpdf(r)
        const = (-2.0 * special.gammaln((nu + n) / 2) + 2.0 * special.gammaln(nu / 2) + n * np.log(nu * np.pi)
                 + 2.0 * n * np.log(s))
        # exact identity up to rounding (the docstring's constant)
        assert student_term(chi2, n, nu) + const == pytest.approx(ref, rel=1e-10, abs=1e-8)


def test_student_term_tends_to_chi2_as_nu_grows_and_is_chi2_without_scatter():
    """(N + nu) ln(1 + c / nu) = c + c (N - c/2) / nu + O(nu^-2): the Gaussian limit; nu = 0 is the Gaussian itself."""
    n, c = 27, np.array([5.0, 27.0, 90.0])
    for nu in (1e4, 1e6, 1e8):
        d = student_term(c, n, int(nu)) - c
        assert np.allclose(d, c * (n - c / 2) / nu, rtol=0.02, atol=1e-9)     # first-order term of the expansion
    assert np.all(student_term(c, n, 0) == c)
    e = Explanation(("a",), 90.0, 2, occam=3.0, occam_student=1.0)
    for m in evidence.EVIDENCE_METHODS:                               # sigma_dof = 0: the two likelihoods agree exactly
        assert e.score(n, m, "student", 0) == e.score(n, m, "gauss", 0)


def test_student_laplace_curvature_matches_quadrature():
    """1-parameter linear model that misfits (chi2_min = 3 N): the Laplace evidence with the Hessian c J^T J,
    c = (N + nu)/(nu + chi2_min), equals -2 ln of the quadrature of (1 + chi2(x)/nu)^(-(N+nu)/2) N(x; mu, sd^2) to
    0.05 (the Laplace error of a 1-D t kernel with N + nu - 1 = 59 dof is O(1/59)); with c = 1 it is off by about
    ln(1/c) = 0.85."""
    n, nu = 40, 20
    rng = np.random.default_rng(1)
    J = rng.normal(0.0, 1.0, (n, 1))
    y = J[:, 0] * 0.7 + rng.normal(0.0, 1.0, n)
    x_hat = float(np.linalg.lstsq(J, y, rcond=None)[0][0])
    base = float(np.sum((y - J[:, 0] * x_hat) ** 2))
    offset = 3.0 * n - base                                           # an unmodelled misfit: chi2(x) = base + offset + A dx^2
    chi2 = lambda x: base + offset + float(J[:, 0] @ J[:, 0]) * (x - x_hat) ** 2
    mu, sd = 0.0, 2.0
    chi2_min = chi2(x_hat)
    T = lambda x: student_term(chi2(x), n, nu)
    ref_T = T(x_hat)
    f = lambda x: np.exp(-0.5 * (T(x) - ref_T)) * stats.norm.pdf(x, mu, sd)
    z, _ = integrate.quad(f, x_hat - 5, x_hat + 5, points=[x_hat], epsabs=1e-14, epsrel=1e-12)
    exact = ref_T - 2.0 * np.log(z)          # -2 ln Z with the normalized prior (laplace_score's convention)
    c = student_curvature(chi2_min, n, nu)
    lap = laplace_score(ref_T, J, np.array([x_hat]), np.array([mu]), np.array([sd]), curvature=c)
    lap1 = laplace_score(ref_T, J, np.array([x_hat]), np.array([mu]), np.array([sd]))
    assert c == pytest.approx((n + nu) / (nu + 3.0 * n))
    assert lap == pytest.approx(exact, abs=0.05)
    assert abs(lap1 - exact) > 0.5


def test_student_weighing_compresses_two_misfitting_rivals():
    """Generated replicate data (3 trials per state, sigma from their scatter, nu = 2 m dof) fitted by two models that
    both misfit a quadratic truth: the Student-t posterior ratio of the two is closer to 1 than the Gaussian one, and
    it is exactly (N + nu) ln((nu + chi2_b) / (nu + chi2_a)) in -2 ln."""
    rng = np.random.default_rng(7)
    m, trials, sigma = 12, 3, 1.0
    t = np.linspace(-1, 1, m)
    truth = 4.0 * t ** 2 + 1.5 * t
    reads = truth[:, None] + rng.normal(0.0, sigma, (m, trials))
    mean = reads.mean(axis=1)
    nu = m * (trials - 1)
    s = np.sqrt(np.sum((reads - mean[:, None]) ** 2) / nu) / np.sqrt(trials)      # sigma of a state's mean
    fits = {}
    for name, X in (("const", np.ones((m, 1))), ("line", np.column_stack([np.ones(m), t]))):
        coef, *_ = np.linalg.lstsq(X, mean, rcond=None)
        fits[name] = (float(np.sum(((mean - X @ coef) / s) ** 2)), X.shape[1])
    assert all(c > 3 * m for c, _ in fits.values())                  # both misfit
    ex = [Explanation((), 1e9, 0)] + [Explanation((k,), c, p) for k, (c, p) in fits.items()]
    g = posterior(ex, m, "bic", "gauss", nu)
    st = posterior(ex, m, "bic", "student", nu)
    lr_g, lr_s = np.log(g[2] / g[1]), np.log(st[2] / st[1])
    assert lr_g > lr_s > 0                                            # same leader, less over-confident
    (ca, _), (cb, _) = fits["const"], fits["line"]
    expect = 0.5 * ((m + nu) * np.log((nu + ca) / (nu + cb)) - np.log(m))   # 1 extra parameter: - ln N / 2 (BIC)
    assert lr_s == pytest.approx(expect, rel=1e-10)                  # the closed form of the Student-t weights


def test_hopeless_pair_bound_holds_in_the_student_quantity():
    """A pair at the stop threshold cannot come within HOPELESS of the best total under any evidence approximation and
    either likelihood, even with the smallest Occam term allowed (-2 k ln 2); the Gaussian-only threshold would be
    too low under Student-t for misfits (the transform compresses large chi^2)."""
    from femcheck.diagnose.selection import HOPELESS, _best_total, _hopeless_pair, _size_prior, _total
    n, nu, k = 30, 48, 4
    prior = _size_prior(8)
    rivals = [Explanation((), 900.0, 0), Explanation(("a",), 400.0, 2, occam=9.0, occam_student=7.0)]
    best = _best_total(rivals, n, prior, nu)
    thr = _hopeless_pair(best, k, prior, n, nu)
    pair = Explanation(("a", "b"), thr * (1 + 1e-9), k, occam=-2 * k * np.log(2), occam_student=-2 * k * np.log(2))
    for lik in evidence.LIKELIHOODS:
        for m in evidence.EVIDENCE_METHODS:
            assert _total(pair, n, prior[2], m, lik, nu) >= best[lik] + HOPELESS - 1e-6
    gauss_only = best["gauss"] + HOPELESS + 2 * k * np.log(2) + 2 * np.log(prior[2])
    assert thr > gauss_only
    below = Explanation(("a", "b"), gauss_only * 1.01, k, occam=0.0, occam_student=0.0)
    assert _total(below, n, prior[2], "bic", "student", nu) < best["student"] + HOPELESS


def test_bad_likelihood_values_are_refused(capsys):
    """One-line error naming the option, exit 2, before any work; the API names the keyword."""
    from femcheck.cli import main
    assert main(["diagnose", "cases/haptic_6psu.toml", "no_such.csv", "--likelihood", "cauchy"]) == 2
    err = capsys.readouterr().err
    assert "--likelihood" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    with pytest.raises(ValueError, match="likelihood"):
        posterior([Explanation((), 1.0, 0)], 3, "bic", "cauchy", 4)
    from femcheck.diagnose import diagnose
    with pytest.raises(ValueError, match="likelihood"):
        diagnose(None, None, likelihood="t")


def test_diagnosis_weighs_by_student_on_request():
    """End to end on a sparse generated set (3 trials: sigma from the scatter, sigma_dof > 0): the weighing is the
    Student-t Laplace posterior of the same fits, every fitted rival carries its Student-t Occam term, the truth is
    named either way, and the JSON states the likelihood."""
    from femcheck.diagnose import diagnose
    from tests.conftest import sparse_actuation_readings
    model, readings = sparse_actuation_readings()
    assert readings.sigma_dof > 0
    pool = ["actuation_compliance", "joint_contact_compliance", "link_modulus"]
    d = diagnose(model, readings, candidates=pool, with_baseline=False, evidence_method="laplace", likelihood="student")
    w = d.weighing
    assert w.likelihood == "student" and w.sigma_dof == readings.sigma_dof
    assert d.as_json()["likelihood"].startswith("Student-t") and d.as_json()["sigma_dof"] == readings.sigma_dof
    assert all(e.occam_student is not None for e in w.explanations if e.n_params)
    # exact re-evaluation of the same fits (the weighing uses the Student-t Laplace posterior, not the Gaussian one)
    st = posterior(w.explanations, w.n_data, "laplace", "student", readings.sigma_dof)
    assert np.allclose(w.probability, st, rtol=1e-12, atol=0)
    assert d.causes[0].id == "actuation_compliance"      # a 1.5x softer drive, the truth, is named either way
