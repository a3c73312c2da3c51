"""Effect library: vocabulary, neutral values, closed-form relations to the analytical models, fitting."""
import numpy as np
import pytest

import femcheck
from femcheck.chain import evaluate
from femcheck.diagnose.effects import VOCABULARY, effects, get_effect
from femcheck.diagnose.fitting import fit_effects
from femcheck.diagnose.model import AnalyticalChainModel, predict_readings
from femcheck.experiment.simulate import simulate
from femcheck.measured import process


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case("cases/haptic_6psu.toml")


@pytest.fixture(scope="module")
def readings(case):
    ve = simulate(case, [], seed=0, directions=("+x", "-y", "+z"))
    return process(ve.data, case)


def test_registry_is_the_issue_vocabulary():
    assert sorted(effects()) == sorted(VOCABULARY)
    with pytest.raises(KeyError, match="expected one of"):
        get_effect("backlash")


@pytest.mark.parametrize("eid", [e for e in VOCABULARY if e != "none"])
def test_neutral_values_reproduce_the_model(case, readings, eid):
    m = AnalyticalChainModel(case, "detailed", "rigid")
    eff = get_effect(eid)
    if not eff.applicable(m):   # an effect that adds what the model lacks: neutral on the level that lacks it
        m = AnalyticalChainModel(case, "simplified", "rigid")
    base = predict_readings(m, readings)
    # neutral parameters are exact identities (scales 1, zero gap/friction/rotation): float rounding only
    np.testing.assert_allclose(predict_readings(m, readings, [eff], [eff.neutral(m)]), base, rtol=1e-12, atol=1e-18)


def test_joint_and_actuation_effects_turn_simplified_into_detailed(case, readings):
    simp = AnalyticalChainModel(case, "simplified", "rigid")
    det = AnalyticalChainModel(case, "detailed", "rigid")
    j, a = get_effect("joint_contact_compliance"), get_effect("actuation_compliance")
    got = predict_readings(simp, readings, [j, a], [np.array([1.0]), np.array([1.0])])
    # same chain, same scales: identical up to the Hertz fixed-point tolerance (1e-12)
    np.testing.assert_allclose(got, predict_readings(det, readings), rtol=1e-9, atol=1e-15)


def test_link_modulus_equals_scaling_the_aluminium_modulus(case, readings):
    """Simplified model (guideways + links, both aluminium): beam compliance ~ 1/E at fixed nu (G ~ E)."""
    f = 1.7
    m = AnalyticalChainModel(case, "simplified", "rigid")
    got = predict_readings(m, readings, [get_effect("link_modulus")], [np.array([f])])
    stiff = case.with_params(**{"materials.aluminium.E_Pa": f * case.material("aluminium").E_Pa})
    W = np.zeros((readings.n_states, 6))
    W[:, :3] = readings.force
    ref = evaluate(stiff, readings.pose, W, model="simplified").twist[:, :3]
    np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-18)   # linear model: exact up to rounding


def test_large_joint_rotation_compliance_approaches_the_released_model(case, readings):
    m = AnalyticalChainModel(case, "detailed", "rigid")
    got = predict_readings(m, readings, [get_effect("joint_rotation_release")], [np.array([1e4])])
    ref = predict_readings(AnalyticalChainModel(case, "detailed", "released"), readings)
    # c = 1e4 rad/(N m) against moment stiffnesses of order 1 N m/rad leaves a ~1e-4 relative residue
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-3 * np.abs(ref).max())


def test_fit_recovers_a_hidden_scale_with_a_covering_interval(case):
    ve = simulate(case, [("actuation_compliance", {"scale": 2.2})], seed=5, directions=("+x", "+y", "+z"))
    r = process(ve.data, case)
    fit = fit_effects(AnalyticalChainModel(case), r, [get_effect("actuation_compliance")])
    lo, hi = fit.params_ci(0)["scale"]
    assert lo < 2.2 < hi
    # 3 um noise on ~0.1 mm deflections over 81 cases pins the scale to about 1 %
    assert fit.params(0)["scale"] == pytest.approx(2.2, rel=0.03)
    assert fit.chi2 / fit.n_data < 1.5 and not fit.warnings


def test_identifiability_warning_for_a_gap_that_is_not_there(readings, case):
    fit = fit_effects(AnalyticalChainModel(case), readings, [get_effect("clearance")])
    # no clearance in the data: the gaps sit at (or near) zero, where neither they nor the closing force are pinned
    assert any(("clearance." in w and "not identifiable" in w) or "singular" in w for w in fit.warnings)
