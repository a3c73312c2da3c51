"""The generic verdict/evidence machinery (issue 15 items 1, 2): closed forms of the chi^2 and F tails,
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
