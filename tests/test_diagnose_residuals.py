"""Residual analysis: errors vanish for a perfect model; each signature responds to its effect."""
import numpy as np
import pytest

import femcheck
from femcheck.diagnose import residuals
from femcheck.diagnose.model import AnalyticalChainModel, predict_readings
from femcheck.experiment.simulate import simulate
from femcheck.measured import process


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case("cases/haptic_6psu.toml")


def _noise_free(case, hidden, level="detailed"):
    ve = simulate(case, hidden, noise_sigma_m=0.0, resolution_m=0.0, level=level, directions=("+x", "+y", "+z"))
    return process(ve.data, case.with_params(**{"measurement.dial_resolution_m": 1e-10}))


def _sig(case, r, level="detailed"):
    pred = predict_readings(AnalyticalChainModel(case, level), r)
    return {s.name: s for s in residuals.signatures(r, pred)}, pred


def test_perfect_model_has_no_error_and_no_signature(case):
    r = _noise_free(case, [])
    sig, pred = _sig(case, r)
    err = residuals.case_errors(r, residuals.case_deltas(r, pred))
    # the CSV prints 1e-9 m on deflections >= 6e-5 m
    assert err["vector"].max() < 1e-4
    for name in ("scale", "nonlinearity", "hysteresis", "cross_talk"):
        assert abs(sig[name].value) < 1e-3, name


def test_scale_signature_of_a_uniformly_softer_linear_device(case):
    """Simplified (linear) model with every compliance x1.25: measured/model = 1.25 everywhere."""
    r = _noise_free(case, [("link_modulus", {"E_factor": 0.8})], level="simplified")
    sig, _ = _sig(case, r, "simplified")
    assert sig["scale"].value == pytest.approx(0.25, abs=1e-4)       # 1e-9 m printing on 1e-4 m deflections
    for a in "xyz":
        assert abs(sig[f"direction:{a}"].value) < 1e-4
    assert sig["scale"].flagged and not sig["hysteresis"].flagged


@pytest.mark.parametrize("hidden, name, sign", [
    (("actuation_compliance", {"scale": 3.0}), "direction:z", +1),        # the rails are vertical: z feels the drive most
    (("friction_hysteresis", {"friction_N": 3.0}), "hysteresis", +1),
    (("clearance", {"gap_x_m": 5e-5, "gap_y_m": 5e-5, "gap_z_m": 5e-5, "closing_force_N": 2.0}), "offset", +1),
    (("hertz_stiffening", {"extra_compliance_at_ref": 5.0}), "nonlinearity", +1),
    (("leg_softening", {"leg1": 3.0}), "leg_asymmetry", +1),
    (("sensor_misalignment", {"theta_z_rad": 0.15}), "cross_talk", +1),
])
def test_signature_flags_its_effect(case, hidden, name, sign):
    r = _noise_free(case, [hidden])
    sig, _ = _sig(case, r)
    assert sig[name].flagged and np.sign(sig[name].value) == sign


def test_seed_table_layout(case):
    r = _noise_free(case, [])
    t = residuals.error_table(r, r.delta * 1.1)
    assert list(t) == ["x", "y", "z"] and list(t["x"]) == [f"P{i}" for i in range(9)] + ["Average"]
    assert t["z"]["Average"] == pytest.approx(10.0, abs=1e-9)    # exact: model = 1.1 x measured
