"""Causes with a place and causes that add what the model lacks.

The default suite runs the cheap checks and the issue's two-leg case (one diagnosis); the slow ones add whole-leg
softening, random omitted scales and the FE storyline (the default storyline test is in test_diagnose_selection.py).
Each test draws its own variety (legs, magnitudes, seeds) from a seeded generator, so that a fixed lucky draw cannot
pass it; tolerances and their reasons are stated at each assertion.
"""
import math

import numpy as np
import pytest

from femcheck.chain import ChainAdjustments, evaluate
from femcheck.diagnose import AnalyticalChainModel, diagnose
from femcheck.diagnose.effects import LOCATED, get_effect
from femcheck.diagnose.model import ACT, predict_readings
from femcheck.diagnose.placement import screen_placements
from femcheck.experiment.simulate import simulate
from femcheck.measured import process

FAST_DIRECTIONS = ("+x", "+y", "+z")


@pytest.fixture(scope="module")
def model(rigid_chain):
    return rigid_chain


def test_located_effect_scales_only_its_legs(case, model):
    """The restricted effect equals the chain evaluated with that element's scale changed in those legs only."""
    rng = np.random.default_rng(1)
    legs = sorted(rng.choice(6, size=2, replace=False).tolist())
    f = rng.uniform(1.5, 3.0, size=2)
    r = process(simulate(case, [], seed=3, directions=FAST_DIRECTIONS).data, case)
    got = predict_readings(model, r, [get_effect("actuation_in_legs").restricted(legs)], [f])
    scale = np.ones((len(r.phase), 6, 5))
    scale[:, legs, ACT] = f
    W = np.zeros((len(r.phase), 6))
    W[:, :3] = r.force
    ref = evaluate(case, r.pose, W, model="detailed", joints="rigid",
                   adjust=ChainAdjustments(element_scale=scale)).twist[:, :3]
    np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-18)   # same chain, same scales: rounding only


def test_placement_penalty_is_the_extended_bic_term():
    """Chen & Chen's 2 ln C(p, k) for k legs among p = 6; all six legs is a fixed model (0)."""
    eff = get_effect("spherical_joint_in_legs")
    for k in range(1, 7):
        assert eff.restricted(range(k)).penalty == pytest.approx(2 * math.log(math.comb(6, k)) if k < 6 else 0.0)


def test_screening_finds_the_hidden_element_and_legs(case, model):
    """Random element type (actuation, guideway, proximal link: not alike at the TCP), 1-2 random legs, a factor
    U(1.8, 3): the screened placement of the hidden type names exactly those legs and ranks first."""
    rng = np.random.default_rng(2026)
    for k, eid in enumerate(("actuation_in_legs", "guideway_in_legs", "proximal_link_in_legs")):
        legs = sorted(rng.choice(6, size=int(rng.integers(1, 3)), replace=False).tolist())
        f = float(rng.uniform(1.8, 3.0))
        r = process(simulate(case, [(eid, {f"leg{i}": f for i in legs})], seed=40 + k, directions=FAST_DIRECTIONS).data,
                    case)
        p = screen_placements(model, r, [get_effect(i) for i in LOCATED])
        assert p[0].effect.id == eid and list(p[0].effect.legs) == legs, (eid, legs, f, [(q.effect.id, q.effect.legs) for q in p])


def test_screening_keeps_a_near_rigid_leg_whose_linear_fit_wants_all_six_legs(case, model):
    """The prior's leg factors are N(1, 1): a proximal link near rigid (0.02-0.1) in one leg, 1.2-1.8x softer in two
    others, 2 points (the calibration bench's sparse protocol, its set 26). The linearization at 1 then fits best with
    all six legs free; that once dropped the type as "an all-legs change" and no placement joined the rivals (2 of
    these 6 draws). The screened placement must be the proximal link and hold the near-rigid leg (the two softer legs
    are at 3-10x the noise and may be traded for a neighbour: not asserted)."""
    import dataclasses as dc
    for s in range(6):
        rng = np.random.default_rng(s)
        legs = sorted(rng.choice(6, size=3, replace=False).tolist())
        rigid = float(rng.uniform(0.02, 0.1))
        vals = {f"leg{i}": float(rng.uniform(1.2, 1.8)) for i in legs}
        vals[f"leg{legs[1]}"] = rigid
        ve = simulate(case, [("proximal_link_in_legs", vals)], seed=50 + s, directions=FAST_DIRECTIONS, sweep=False)
        keep = np.isin(ve.data.point, ("P2", "P7"))
        data = dc.replace(ve.data, **{k: getattr(ve.data, k)[keep] for k in
                                      ("point", "direction", "trial", "phase", "load_N", "force", "disp", "row")})
        p = screen_placements(model, process(data, case), [get_effect(i) for i in LOCATED])
        assert p and p[0].effect.id == "proximal_link_in_legs" and legs[1] in p[0].effect.legs, \
            (vals, [(q.effect.id, q.effect.legs) for q in p])
        # the near-rigid leg is thousands of chi^2 units off the model as given: far beyond any noise
        assert p[0].score < 0.1 * p[0].score_none, (vals, p[0].score, p[0].score_none)


def test_diagnosis_refines_more_element_types_than_it_lets_join(case, model):
    """A guideway near rigid (0.02-0.2) in two legs and 0.9-2.1x in three others, 2 points, one direction (the
    calibration bench's set 32). Linearized at scale 1 the proximal link ranks first; refined nonlinearly the guideway
    wins by hundreds of chi^2. With ``max_located`` = 1 the diagnosis once refined only the linear first (the wrong
    type in 2 of these 3 draws); it refines three and lets the best refined placement join. The legs are not asserted:
    24 readings cannot separate a near-rigid leg's placement from its neighbours'."""
    import dataclasses as dc
    for s in range(3):
        rng = np.random.default_rng(s)
        legs = sorted(rng.choice(6, size=5, replace=False).tolist())
        vals = {f"leg{i}": float(rng.uniform(0.9, 2.1)) for i in legs}
        for i in rng.choice(legs, size=2, replace=False):
            vals[f"leg{i}"] = float(rng.uniform(0.02, 0.2))
        ve = simulate(case, [("guideway_in_legs", vals)], seed=60 + s, directions=("-y",), sweep=False)
        keep = np.isin(ve.data.point, ("P2", "P6"))
        data = dc.replace(ve.data, **{k: getattr(ve.data, k)[keep] for k in
                                      ("point", "direction", "trial", "phase", "load_N", "force", "disp", "row")})
        d = diagnose(model, process(data, case), with_baseline=False, max_located=1)
        assert len(d.placements) == 1 and d.placements[0].effect.id == "guideway_in_legs", \
            (vals, [(q.effect.id, q.effect.legs) for q in d.placements])


def test_actuation_softer_in_two_random_legs_is_named_with_its_legs(case, model):
    """The issue's case: two legs whose actuation is 1.8x softer came back as leg_softening plus a spurious
    link_modulus x 1.19. Now: one cause, actuation in exactly those legs, factors within 5 % of 1.8."""
    rng = np.random.default_rng(15)
    legs = sorted(rng.choice(6, size=2, replace=False).tolist())
    seed = int(rng.integers(100, 1000))
    r = process(simulate(case, [("actuation_in_legs", {f"leg{i}": 1.8 for i in legs})], seed=seed,
                         directions=FAST_DIRECTIONS).data, case)
    d = diagnose(model, r, with_baseline=False)
    assert d.verdict == "explained", (d.verdict, [c.id for c in d.causes])
    assert [c.id for c in d.causes] == ["actuation_in_legs"], [(c.id, c.location) for c in d.causes]
    c = d.causes[0]
    assert list(c.legs) == legs and c.element == "act"
    assert c.probability > 0.9   # nothing else in the vocabulary fits these data within noise
    for i in legs:   # 3 um noise on ~50 um deflections through 0.01 mm dials: a few % on the factor
        assert c.params[f"leg{i}"] == pytest.approx(1.8, rel=0.05)
        lo, hi = c.params_ci[f"leg{i}"]
        assert lo - 0.02 < 1.8 < hi + 0.02
    js = d.as_json()["causes"][0]
    assert js["legs"] == legs and js["element"] == "act" and js["location"].endswith(", ".join(map(str, legs)))


@pytest.mark.slow
def test_whole_leg_softening_is_not_taken_for_one_element(case, model):
    """A whole leg softer (all five elements) stays leg_softening: no single element type reproduces it."""
    rng = np.random.default_rng(7)
    leg = int(rng.integers(0, 6))
    f = float(rng.uniform(2.5, 4.0))
    r = process(simulate(case, [("leg_softening", {f"leg{leg}": f})], seed=int(rng.integers(1000)),
                         directions=FAST_DIRECTIONS).data, case)
    d = diagnose(model, r, with_baseline=False)
    assert d.causes[0].id == "leg_softening" and d.causes[0].location == f"legs {leg}", \
        [(c.id, c.location) for c in d.causes]


@pytest.mark.slow
def test_fe_device_against_the_simplified_model_names_the_missing_compliance(case):
    """The paper's storyline on FE-made data (device FE with frictional contact joints, beam parts, coarse mesh):
    the simplified model lacks the drive and the joints; the diagnosis adds them (missing_compliance) instead of a
    stand-in on its bound."""
    from femcheck.diagnose.fe_model import DeviceFEReadingModel
    from femcheck.kinematics.psu6 import POINT_LABELS
    from femcheck.verify.fe import run_fe
    fe = DeviceFEReadingModel(case, run_fe(case, POINT_LABELS, ("detailed",), "coarse", jobs=1, kind="beam"))
    r = process(simulate(case, [], seed=int(np.random.default_rng(4).integers(1000)), model=fe,
                         directions=FAST_DIRECTIONS).data, case)
    d = diagnose(AnalyticalChainModel(case, "simplified", "rigid"), r, with_baseline=False)
    assert d.causes[0].id == "missing_compliance", [(c.id, c.location, c.on_bound) for c in d.causes]
    assert not any(c.on_bound for c in d.causes) and "clearance" not in [c.id for c in d.causes]
    # the added elements take the error from tens of percent to a few (the FE's contact law is not the chain's)
    assert d.heldout_error_before["overall"] > 0.3 and d.heldout_error_after["overall"] < 0.1


@pytest.mark.slow
def test_random_omitted_compliance_is_added_back(case):
    """Data from the simplified model plus drive and joints at random scales U(0.7, 1.5) of their formulas: the
    diagnosis against the simplified model names the one omission, missing_compliance, and recovers the drive."""
    from femcheck.bench.hidden_effects import run_case
    seed = int(np.random.default_rng(33).integers(10_000))
    r = run_case(case, "missing_compliance", seed=seed, directions=FAST_DIRECTIONS)
    assert r.named[:1] == ("missing_compliance",), (r.named, r.truth)
    assert r.drop >= 0.5, (r.error_before, r.error_after)   # acceptance of issue 7: held-out error at least halved


def _sparse(data, points):
    import dataclasses as dc
    keep = np.isin(data.point, points)
    return dc.replace(data, **{k: getattr(data, k)[keep] for k in
                               ("point", "direction", "trial", "phase", "load_N", "force", "disp", "row")})


def test_located_partner_of_a_dominant_cause_is_placed_on_what_that_cause_leaves(case, model):
    """A pair (the calibration bench's seed-0 set 17): a dial misaligned by 0.04-0.08 rad about each axis dominates
    the residual; the proximal link is 1.8-3x softer in two random legs; 6 points, +x/+y/+z (at 3 points the
    misalignment and a four-leg placement with one leg stiffer fit as well as the truth: not identifiable). Screened on the residual of
    the model as given, the located cause came out as another element type or other legs (the misalignment's
    residual is what it fits), so the true pair was never weighed. Screened again after the fitted misalignment
    (``background``), the placement is the proximal link in exactly the hidden legs, and the diagnosis gives that
    pair most of the mass (it was 0 before: the pair with the right placement was not among the rivals)."""
    from femcheck.diagnose.fitting import fit_effects
    rng = np.random.default_rng(17)
    located = [get_effect(i) for i in LOCATED]
    sensor = get_effect("sensor_misalignment")
    for s in range(2):
        legs = sorted(rng.choice(6, size=2, replace=False).tolist())
        vals = {f"leg{i}": float(rng.uniform(1.8, 3.0)) for i in legs}
        rot = {k: float(rng.choice([-1, 1]) * rng.uniform(0.04, 0.08)) for k in ("theta_x_rad", "theta_y_rad", "theta_z_rad")}
        ve = simulate(case, [("sensor_misalignment", rot), ("proximal_link_in_legs", vals)], seed=90 + s,
                      directions=FAST_DIRECTIONS, sweep=False)
        # six points: at five (P0, P1, P4, P6, P8) the second leg was resolved only while the reading sigma was pooled
        # over axes that read zero throughout (their scatter hidden by the rounding, sigma too small)
        r = process(_sparse(ve.data, ("P0", "P1", "P2", "P4", "P6", "P8")), case)
        f = fit_effects(model, r, [sensor])
        p = screen_placements(model, r, located, background=([sensor], list(f.values)))
        assert p and p[0].effect.id == "proximal_link_in_legs" and list(p[0].effect.legs) == legs, \
            (vals, rot, [(q.effect.id, q.effect.legs, q.score) for q in p])
        # what the misalignment leaves is the located cause at ~10-30x the noise: the placement takes it to noise
        # (chi^2 within a few times N = 216 readings, from thousands)
        assert p[0].score < 0.2 * p[0].score_none, (p[0].score, p[0].score_none)
        if s == 0:
            d = diagnose(model, r, with_baseline=False)
            marg = {}
            for ex, q in zip(d.weighing.explanations, d.weighing.probability):
                for i in ex.ids:
                    marg[i] = marg.get(i, 0.0) + q
            # both hidden causes are named with most of the mass: the pair fits to noise, every rival is far off
            assert marg.get("proximal_link_in_legs", 0.0) > 0.9 and marg["sensor_misalignment"] > 0.9, marg
            named = {c.id: c for c in d.causes}
            assert list(named["proximal_link_in_legs"].legs) == legs, [(c.id, c.legs) for c in d.causes]


def test_located_probability_is_shared_between_placements_the_data_cannot_separate(case, model):
    """A spherical joint 1.8-3x softer in one random leg, 3 points, +x/+y/+z: the universal joint of the same leg sits
    next to it and fits almost as well (Delta BIC of a few units). With only the best refined placement weighed, the
    other type got probability 0; now both placements are weighed and share the located mass (the two together hold
    nearly all of it)."""
    rng = np.random.default_rng(3)
    for s in range(2):
        leg = int(rng.integers(6))
        f = float(rng.uniform(1.8, 3.0))
        ve = simulate(case, [("spherical_joint_in_legs", {f"leg{leg}": f})], seed=80 + s, directions=FAST_DIRECTIONS,
                      sweep=False)
        d = diagnose(model, process(_sparse(ve.data, ("P0", "P3", "P5")), case), with_baseline=False)
        marg = {}
        for ex, q in zip(d.weighing.explanations, d.weighing.probability):
            for i in ex.ids:
                marg[i] = marg.get(i, 0.0) + q
        weighed = [(q.effect.id, q.effect.legs) for q in d.placements + d.partner_placements]
        assert ("universal_joint_in_legs", (leg,)) in weighed, (leg, f, weighed)
        sp, uj = marg.get("spherical_joint_in_legs", 0.0), marg.get("universal_joint_in_legs", 0.0)
        # shared: each keeps more than 1e-3 (one of them got exactly 0 before): the S and U joint of one leg differ at
        # three points by a Delta BIC below 2 ln 1000 ~ 14 (the two draws: 0.67 / 0.29, 0.993 / 0.0075); which one
        # leads is up to the noise. Together they hold >= 85 % (the rest: pairs that add a cause within noise)
        assert uj > 1e-3 and sp > 1e-3 and sp + uj > 0.85, (leg, f, marg)


def test_located_siblings_weigh_every_element_type_of_the_placed_legs(case, model):
    """Opt-in ``located_siblings``: the legs a screen keeps are weighed with every other element type too (a drive, a
    guideway and the two joints of a leg act in series). Without the option the guideway of the placed leg is not
    weighed on this set; with it, all five element types of that leg are."""
    leg = 2
    ve = simulate(case, [("actuation_in_legs", {f"leg{leg}": 2.5})], seed=91, directions=FAST_DIRECTIONS, sweep=False)
    readings = process(_sparse(ve.data, ("P0", "P3", "P5")), case)
    types = set(LOCATED)
    weighed = {}
    for opt in (False, True):
        d = diagnose(model, readings, with_baseline=False, located_siblings=opt)
        weighed[opt] = {q.effect.id for q in d.placements + d.partner_placements if q.effect.legs == (leg,)}
    placed = next(q.effect.legs for q in d.placements)
    assert placed == (leg,), placed
    # the option adds the types: every element type of the placed leg is weighed with it, fewer without it
    assert types <= weighed[True], weighed
    assert weighed[False] < weighed[True], weighed


def test_linearized_placement_evidence_is_the_gaussian_marginal_likelihood():
    """:func:`subset_scores` against the closed form: for r0 = G_L x + e, x ~ N(0, W^2), e ~ N(0, I), the evidence is
    the density of r0 under N(0, I + G_L W^2 G_L^T) (Bishop PRML eq. 3.86); the chi^2 is that of the ridge (MAP)
    step, solved here with the normal equations written out. Random G,
    residual, prior widths and subsets (all 63 placements checked, all six legs included)."""
    from scipy import stats

    from femcheck.diagnose.placement import subset_scores
    rng = np.random.default_rng(7)
    for _ in range(3):
        n = int(rng.integers(12, 40))
        G = rng.normal(size=(n, 6)) * rng.uniform(0.5, 20.0, size=6)
        r0 = rng.normal(size=n) * rng.uniform(1.0, 3.0)
        sd = rng.uniform(0.3, 2.0, size=6)
        subsets, sc = subset_scores(G, r0, sd, np.zeros(6), n)
        assert len(subsets) == 63   # 2^6 - 1 non-empty leg sets
        for i, L in enumerate(subsets):
            GL = G[:, list(L)]
            cov = np.eye(n) + GL @ np.diag(sd[list(L)] ** 2) @ GL.T
            exact = -2.0 * stats.multivariate_normal(np.zeros(n), cov).logpdf(r0) - n * math.log(2 * math.pi)
            pen = 2.0 * math.log(math.comb(6, len(L)))
            # same quantity, two factorizations (Woodbury / Sylvester against the n x n density): rounding only
            assert sc[("laplace", "gauss")][i] - pen == pytest.approx(exact, rel=1e-9, abs=1e-8)
            x_map = np.linalg.solve(GL.T @ GL + np.diag(sd[list(L)] ** -2.0), GL.T @ r0)   # ridge = the prior
            chi2 = float(np.sum((r0 - GL @ x_map) ** 2))
            assert sc["chi2"][i] == pytest.approx(chi2, rel=1e-8, abs=1e-8)
            assert sc[("bic", "gauss")][i] == pytest.approx(chi2 + len(L) * math.log(n) + pen, rel=1e-8, abs=1e-8)


def test_located_cause_below_the_detection_limit_keeps_its_discounted_prior(case, model):
    """No effect hidden (3 random points, +x/+y/+z): no placement beats none, so before the unweighed placements
    were summed every element type in legs had probability exactly 0, while a located change too small to see is as
    likely as its prior times its Occam factor (the calibration bench: located causes given < 0.1 were right 3.4 %
    of the time against 0.2 % predicted). Now each type keeps a share: positive, and below none's (the data favour
    no change)."""
    rng = np.random.default_rng(11)
    points = tuple(sorted(rng.choice(["P0", "P1", "P2", "P3", "P4", "P5", "P6", "P7", "P8"], size=3, replace=False)))
    ve = simulate(case, [], seed=int(rng.integers(1000)), directions=FAST_DIRECTIONS, sweep=False)
    readings = process(_sparse(ve.data, points), case)
    marg = {}
    for opt in (False, True):
        d = diagnose(model, readings, with_baseline=False, unweighed_mass=opt)
        m = {t: 0.0 for t in LOCATED}
        for ex, q in zip(d.weighing.explanations, d.weighing.probability):
            for i in ex.ids:
                if i in m:
                    m[i] += q
        p_none = next(q for ex, q in zip(d.weighing.explanations, d.weighing.probability) if not ex.ids)
        marg[opt] = (m, p_none, d.verdict)
    m0, _, _ = marg[False]
    m1, p_none, verdict = marg[True]
    assert verdict == "none", verdict
    assert min(m0.values()) == 0.0, m0                       # the defect this guards: a type never placed got 0
    # each type: more than 1e-4 (the prior share of a single is ~1/45 here; an Occam factor of a few e-2 per leg
    # still leaves > 1e-4), less than none's (nothing was hidden)
    assert all(1e-4 < v < p_none for v in m1.values()), (m1, p_none)


def test_linearized_placement_evidence_respects_the_bounds_and_the_full_model():
    """Two guards of :func:`subset_scores`. (1) A compliance scale cannot go below 0: with ``lower`` the MAP step is
    the bounded one, so chi^2 can only rise, and exactly where the free step crosses the bound (invariant of a
    constrained minimum). (2) ``chi2_at``: the scores move one for one with the full model's chi^2 at the step (a
    model that fits 10 worse there scores 10 worse under both evidences)."""
    from femcheck.diagnose.placement import subset_scores
    rng = np.random.default_rng(8)
    n = 30
    G = rng.normal(size=(n, 6)) * rng.uniform(1.0, 10.0, size=6)
    r0 = G @ rng.uniform(-3.0, 1.0, size=6) + rng.normal(size=n)   # some legs' best steps are below -1
    sd = np.ones(6)
    lower = -np.ones(6)
    subsets, free = subset_scores(G, r0, sd, np.zeros(6), n)
    _, bound = subset_scores(G, r0, sd, np.zeros(6), n, lower=lower)
    rows = []
    for i, L in enumerate(subsets):
        GL = G[:, list(L)]
        x = np.linalg.solve(GL.T @ GL + np.eye(len(L)), GL.T @ r0)
        crosses = bool((x < lower[list(L)]).any())
        rows.append(crosses)
        # rounding only where the bound is inactive; at least 1e-9 above where it binds (a strict constrained rise)
        if crosses:
            assert bound["chi2"][i] > free["chi2"][i] + 1e-9, L
        else:
            assert bound["chi2"][i] == pytest.approx(free["chi2"][i], rel=1e-12, abs=1e-9), L
    assert 0 < sum(rows) < len(rows)   # the draw exercises both branches
    linear_chi2 = lambda X: np.sum((r0[None] - X @ G.T) ** 2, axis=1)   # the linear model itself, at the steps
    _, same = subset_scores(G, r0, sd, np.zeros(6), n, chi2_at=linear_chi2)
    _, worse = subset_scores(G, r0, sd, np.zeros(6), n, chi2_at=lambda X: linear_chi2(X) + 10.0)
    best = np.argmin(free[("bic", "gauss")])
    near = free[("bic", "gauss")] <= free[("bic", "gauss")].min() + 20.0
    for key in (("bic", "gauss"), ("laplace", "gauss")):
        np.testing.assert_allclose(same[key], free[key], rtol=1e-9)   # the steps and chi^2 the linear algebra had
        shift = worse[key] - free[key]
        # only the placements near the best are evaluated (NONLINEAR_MARGIN 20), and those move by exactly 10
        assert np.allclose(shift[near], 10.0) and shift[best] == pytest.approx(10.0), shift
        assert np.all(np.isclose(shift, 0.0) | np.isclose(shift, 10.0)), shift
