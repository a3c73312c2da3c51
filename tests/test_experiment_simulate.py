"""Virtual experiment: protocol structure, agreement with the analytical model, physics of
hidden effects, the CLI's refusal to overwrite."""
import json

import numpy as np
import pytest

import femcheck
from femcheck.chain import evaluate
from femcheck.cli import main
from femcheck.experiment.simulate import ALL_DIRECTIONS, SWEEP_LOADS_N, parse_effect_spec, simulate
from femcheck.measured import process


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case("cases/haptic_6psu.toml")


def test_protocol_rows_and_quantization(case):
    ve = simulate(case, [], seed=0)
    n_dir, trials = len(ALL_DIRECTIONS), case.measurement.trials
    # per trial: 9 points x directions x (preload, total, unload@Pp, unload@0) + the P0 staircase per direction
    assert len(ve.data) == trials * (9 * n_dir * 4 + n_dir * len(SWEEP_LOADS_N))
    q = ve.data.disp / case.measurement.dial_resolution_m
    # readings are whole multiples of the 0.01 mm dial step (float rounding of mm -> m only)
    np.testing.assert_allclose(q, np.round(q), rtol=0, atol=1e-6)
    assert "truth" not in ve.csv_text and "scale" not in ve.csv_text
    assert ve.truth["effects"][0]["id"] == "none"


def test_noise_free_readings_equal_the_detailed_model(case):
    ve = simulate(case, [], noise_sigma_m=0.0, resolution_m=0.0, directions=("+x", "-z"), sweep=False)
    r = process(ve.data, case.with_params(**{"measurement.dial_resolution_m": 1e-12}))
    W = np.zeros((r.n_cases, 6))
    W[:, :3] = r.force[r.total_state]
    Wp = np.zeros_like(W)
    Wp[:, :3] = r.force[r.preload_state]
    expect = evaluate(case, r.case_pose, W).twist[:, :3] - evaluate(case, r.case_pose, Wp).twist[:, :3]
    # the CSV prints mm with 3 decimals at resolution 0 -> 6 significant digits: 1e-9 m absolute
    np.testing.assert_allclose(r.delta, expect, rtol=0, atol=1e-9)


def test_friction_hysteresis_on_the_linear_model(case):
    """Simplified (linear) model: loading at F reads S (F - f), unloading to P_p reads S (P_p + f)."""
    f = 2.0
    ve = simulate(case, [("friction_hysteresis", {"friction_N": f})], noise_sigma_m=0.0, resolution_m=0.0,
                  level="simplified", directions=("+x",), sweep=False)
    r = process(ve.data, case.with_params(**{"measurement.dial_resolution_m": 1e-12}))
    pose = r.case_pose[:1]
    S = evaluate(case, pose, [1.0, 0, 0, 0, 0, 0], model="simplified").twist[0, 0]    # m per N
    at = lambda ph, load: r.disp[(r.phase == ph) & (r.point == "P0") & (r.load_N == load)][0, 0]
    Pp, Pt = case.loads.detailed_preload_N, case.loads.detailed_preload_N + case.loads.detailed_test_N
    # the CSV prints mm with 6 decimals at resolution 0: 5e-10 m rounding
    assert at("preload", Pp) == pytest.approx(S * (Pp - f), rel=0, abs=1e-9)
    assert at("total", Pt) == pytest.approx(S * (Pt - f), rel=0, abs=1e-9)
    assert at("unload", Pp) == pytest.approx(S * (Pp + f), rel=0, abs=1e-9)
    assert at("unload", 0.0) == pytest.approx(S * f, rel=0, abs=1e-9)


def test_sensor_misalignment_rotates_the_readings(case):
    th = np.array([0.0, 0.0, 0.2])
    base = simulate(case, [], noise_sigma_m=0.0, resolution_m=0.0, directions=("+x",), sweep=False)
    rot = simulate(case, [("sensor_misalignment", {"theta_z_rad": 0.2})], noise_sigma_m=0.0, resolution_m=0.0,
                   directions=("+x",), sweep=False)
    R = femcheck.kinematics.frames.rotvec_to_matrix(th)
    # printed to 1e-9 m
    np.testing.assert_allclose(rot.data.disp, base.data.disp @ R.T, rtol=0, atol=2e-9)


def test_effect_spec_parsing():
    assert parse_effect_spec("leg_softening:leg2=3,leg4=1.5") == ("leg_softening", {"leg2": 3.0, "leg4": 1.5})
    assert parse_effect_spec("clearance") == ("clearance", {})
    for bad in ("nonsense", "clearance:gap_q_m=1", "clearance:gap_x_m", "clearance:gap_x_m=abc"):
        with pytest.raises(KeyError):
            parse_effect_spec(bad)


def test_cli_simulate_writes_csv_and_truth_and_refuses_overwrite(tmp_path, capsys):
    out, truth = tmp_path / "d.csv", tmp_path / "t.json"
    args = ["experiment", "simulate", "cases/haptic_6psu.toml", "--effect", "actuation_compliance:scale=2",
            "--seed", "4", "--out", str(out), "--truth", str(truth), "--directions", "+x,+z"]
    assert main(args) == 0
    t = json.loads(truth.read_text())
    assert t["effects"][0] == {"id": "actuation_compliance", "params": {"scale": 2.0},
                               "location": "actuation (cable and motor, all legs)"}
    text = out.read_text()
    assert main(args) == 2 and "refusing to overwrite" in capsys.readouterr().err
    assert out.read_text() == text
    assert main(args + ["--force"]) == 0
    assert main(["experiment", "simulate", "cases/haptic_6psu.toml", "--out", "cases/haptic_6psu.toml",
                 "--truth", str(tmp_path / "x.json")]) == 2
