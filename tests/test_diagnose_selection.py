"""Hidden-effect tests: the pipeline must find what was hidden in simulated data.

Default suite: one seeded case per vocabulary id (random magnitude and location, with noise) plus the
paper's storyline and the released-joints analogue. The full matrix (10 seeds per id) is marked slow and
writes reports/diagnose/confusion.md.
"""
import numpy as np
import pytest

import femcheck
from femcheck.diagnose import AnalyticalChainModel, diagnose, residuals
from femcheck.diagnose.effects import LOCATED, VOCABULARY
from femcheck.bench.hidden_effects import confusion_markdown, run_case, run_matrix
from femcheck.experiment.simulate import simulate
from femcheck.measured import process


#: the default suite uses the paper's three load directions (half the readings of the full +- protocol) for speed
FAST_DIRECTIONS = ("+x", "+y", "+z")


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case("cases/haptic_6psu.toml")


#: run by `make test-all` only (the default suite keeps the other six within the CI budget; the same effects are
#: named in the calibration bench and, joint_rotation_release, in test_released_joint_data_against_the_rigid_model)
_SLOW_HIDDEN = {"joint_rotation_release", "leg_softening", "hertz_stiffening", "joint_contact_compliance"}


@pytest.mark.parametrize("hidden", [pytest.param(h, marks=pytest.mark.slow) if h in _SLOW_HIDDEN else h
                                    for h in VOCABULARY if h not in LOCATED and h != "missing_compliance"])
def test_hidden_effect_is_named(case, hidden):
    """(The located ``*_in_legs`` effects and ``missing_compliance`` have their own tests: test_diagnose_located.py.)"""
    r = run_case(case, hidden, seed=1000 * (VOCABULARY.index(hidden) + 1), directions=FAST_DIRECTIONS)
    if hidden == "none":
        assert r.named == ("none",) and not r.significant
        return
    assert r.named[0] == hidden, (r.named, r.truth)
    # acceptance: the held-out error falls by at least half
    assert r.drop >= 0.5, (r.error_before, r.error_after)
    if r.location_match is not None:
        assert r.location_match, (r.location, r.truth)


def test_two_hidden_effects_are_both_named(case):
    """Greedy forward selection: friction above the preload hides a softer drive from a one-step search."""
    hidden = [("friction_hysteresis", {"friction_N": 9.0}), ("actuation_compliance", {"scale": 2.5})]
    r = process(simulate(case, hidden, seed=11, directions=FAST_DIRECTIONS).data, case)
    d = diagnose(AnalyticalChainModel(case, "detailed", "rigid"), r, with_baseline=False)
    assert [c.id for c in d.causes] == ["friction_hysteresis", "actuation_compliance"]
    assert d.causes[0].params_ci["friction_N"][0] < 9.0 < d.causes[0].params_ci["friction_N"][1]
    assert d.heldout_error_after["overall"] < 0.5 * d.heldout_error_before["overall"]


def test_storyline_detailed_data_against_the_simplified_model(case):
    """Seed 000: the simplified model misses the passive joints and the actuation (Table 2 -> Table 3)."""
    ve = simulate(case, [], seed=7, directions=FAST_DIRECTIONS)
    r = process(ve.data, case)
    d = diagnose(AnalyticalChainModel(case, "simplified", "rigid"), r)
    # one cause that adds the omitted elements, not two scales standing in for them
    assert [c.id for c in d.causes] == ["missing_compliance"] and d.verdict == "explained"
    assert not d.causes[0].on_bound
    before = d.cv_before.error_along
    # docs/conventions.md §9: simplified vs detailed 38 / 38 / 73 % (x / y / z); +-5 points for the 3 um noise
    assert before["x"] == pytest.approx(38.3e-2, abs=0.05) and before["z"] == pytest.approx(73.2e-2, abs=0.05)
    # "from tens of percent to below 10 %", per direction, on held-out points
    assert max(d.cv_after.error_along[a] for a in "xyz") < 0.10
    assert d.heldout_error_after["overall"] < 0.10
    # the physical extension beats seed 001's black-box weight fit on held-out points
    assert d.heldout_error_after["overall"] < d.baseline_error["overall"]
    # the added drive is the case's formula (the detailed model made the data): its 95 % interval covers 1
    lo, hi = d.causes[0].params_ci["actuation_scale"]
    assert lo - 0.05 < 1.0 < hi + 0.05
    # the two joint types trade off against each other under +x/+y/+z loads (both sit in series with the links):
    # each within 50 % of the formula
    for name in ("spherical_joint_scale", "universal_joint_scale"):
        assert 0.5 < d.causes[0].params[name] < 1.5, (name, d.causes[0].params)


def test_released_joint_data_against_the_rigid_model(case):
    """Analytical stand-in for the FE acceptance: data from the released model, diagnosed against rigid."""
    ve = simulate(case, [], seed=8, joints="released", directions=FAST_DIRECTIONS)
    r = process(ve.data, case)
    d = diagnose(AnalyticalChainModel(case, "detailed", "rigid"), r, with_baseline=False)
    assert d.causes[0].id == "joint_rotation_release"
    rel = AnalyticalChainModel(case, "detailed", "released")
    from femcheck.diagnose.model import predict_readings
    err_released = residuals.mean_by_axis(r, residuals.case_errors(
        r, residuals.case_deltas(r, predict_readings(rel, r)))["vector"])["overall"]
    assert d.heldout_error_before["overall"] > 0.5
    # "down to the level of the released model": within one noise-floor point of it
    assert d.heldout_error_after["overall"] < err_released + 0.01


@pytest.mark.slow
def test_full_hidden_effect_matrix(tmp_path):
    """10 seeds per id: >= 90 % named correctly, >= 90 % with a >= 50 % drop, `none` >= 90 %."""
    res = run_matrix(VOCABULARY, range(10), jobs=2)
    md = confusion_markdown(res)
    from femcheck.report.atomic import write_text_atomic
    write_text_atomic("reports/diagnose/confusion.md", "# Hidden-effect matrix (tests/test_diagnose_selection.py)\n\n" + md + "\n")
    print(md)
    for h in VOCABULARY:
        rs = [r for r in res if r.hidden == h]
        assert np.mean([r.match for r in rs]) >= 0.9, h
        if h != "none":
            assert np.mean([r.drop >= 0.5 for r in rs]) >= 0.9, h
