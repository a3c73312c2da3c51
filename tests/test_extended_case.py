"""Corrected cases written by ``diagnose --extended-case`` and ``identify --extended-case``: round trips on seeded,
generated data.

Each round trip: the written case loads; its predictions at the measured states equal the fit's "after"
predictions; a diagnosis of the written case against the same data names no further cause. The fit's own tolerance
is the noise: the refit stops at a relative chi^2 change of 1e-6, i.e. predictions settle to ~1e-3 sigma, so the
round trip must agree to far below that (1e-6 sigma is asserted; the keys hold the fitted values, written with
``repr``, so only rounding separates them: by construction).
"""
from __future__ import annotations

import copy
import json
import tomllib

import numpy as np
import pytest

from femcheck.cli import main

SIGMA = 5e-5


# ---------------------------------------------------------------------------------------------------------------
# serial tree: torsion + tilt, with a coupled (passive) row
# ---------------------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    from femcheck.robot.positions import format_marker_csv
    from femcheck.robot.simulate import _build, industrial_case, scaled, simulate_positions, to_toml
    _, raw = industrial_case(1, springs=True)
    raw = copy.deepcopy(raw)
    raw["joints"][5]["coupling"] = {"j5": 0.5}          # the last row turns with half of j5 (a passive, coupled row)
    case = _build(raw)
    eff = {**scaled(case, {"joint_torsion_compliance": {"j2": 1.0}}, 6 * SIGMA),
           **scaled(case, {"joint_tilt_compliance": {"j4": 1.0}}, 6 * SIGMA)}
    data, _ = simulate_positions(case, 120, effects=eff, seed=12, sigma_m=SIGMA, passes=2)
    tmp = tmp_path_factory.mktemp("serial")
    (tmp / "robot.toml").write_text("# a generated arm; this comment must survive\n" + to_toml(raw))
    (tmp / "data.csv").write_text(format_marker_csv(data, case.tree.marker_names))
    q = np.deg2rad(np.array([[0, 0, 0, 0, 0], [10, -30, 40, 20, -50], [-60, 45, -20, 90, 30]], float))
    (tmp / "poses.csv").write_text("pose,q1_rad,q2_rad,q3_rad,q4_rad,q5_rad,payload_kg\n" +
                                   "".join(f"c{i},{','.join(repr(float(v)) for v in row)},0\n" for i, row in enumerate(q)))
    return tmp, case, eff, q


def test_serial_round_trip(serial, capsys):
    """torsion + tilt named; the corrected case reproduces the fit's readings and explains the data by itself."""
    from femcheck.case.registry import load_case
    from femcheck.robot.corrected_case import elastic_deflection, sensor_readings
    from femcheck.robot.diagnosis import diagnose_tree
    from femcheck.robot.positions import read_marker_csv
    tmp, case, eff, q = serial
    out, comp, js = tmp / "robot_ext.toml", tmp / "comp.csv", tmp / "d.json"
    assert main(["diagnose", str(tmp / "robot.toml"), str(tmp / "data.csv"), "--json", str(js),
                 "--extended-case", str(out), "--compensation", str(comp), "--poses", str(tmp / "poses.csv")]) == 0
    j = json.loads(js.read_text())
    assert j["verdict"] == "explained"
    assert sorted(c["id"] for c in j["causes"]) == ["joint_tilt_compliance", "joint_torsion_compliance"]
    text = out.read_text()
    assert text.startswith("# a generated arm; this comment must survive")        # a copy of the case, comments kept
    assert "from joint_torsion_compliance" in text and "from joint_tilt_compliance" in text and "95 % [" in text
    ext = load_case(out)
    doc = tomllib.loads(text)
    assert doc["joints"][5]["coupling"] == {"j5": 0.5}
    # the fit's "after" predictions, recomputed (the diagnosis is deterministic) to compare with the written case
    data = read_marker_csv(tmp / "data.csv", case.tree.marker_names, case.tree.n_joints)
    d = diagnose_tree(case, data)
    pred = sensor_readings(ext, data.q, data.payload_kg)[data.pose, data.marker]
    diff = float(np.abs(pred - d.fitted["predicted"]).max())
    print(f"serial round trip: largest prediction difference {diff:.3g} m")
    assert diff < 1e-6 * SIGMA      # module docstring: the keys are the fitted values (rounding only)
    # the corrected case against the same data: nothing further above the noise
    d2 = diagnose_tree(ext, data).as_json()
    assert d2["verdict"] == "none", (d2["verdict"], [c["id"] for c in d2["causes"]])
    # compensation table = the corrected case's own elastic deflection at the listed poses (printed to 1e-6 mm)
    rows = [l.split(",") for l in comp.read_text().splitlines() if l and not l.startswith(("#", "pose"))]
    got = np.array([[float(v) for v in r[2:]] for r in rows]).reshape(len(q), -1, 3)
    ref = elastic_deflection(ext, q, np.zeros(len(q))) * 1e3
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-6)
    assert np.abs(ref).max() > 0.05    # the table is not trivially zero: tenths of a mm under self weight


def test_serial_refusals(serial, capsys):
    """OUT == CASE is refused (exit 2) before any work; --compensation without --poses too."""
    tmp, *_ = serial
    before = (tmp / "robot.toml").read_text()
    assert main(["diagnose", str(tmp / "robot.toml"), str(tmp / "data.csv"), "--extended-case",
                 str(tmp / "robot.toml")]) == 2
    assert "input file" in capsys.readouterr().err.replace("\n", " ") + ""
    assert (tmp / "robot.toml").read_text() == before
    assert main(["diagnose", str(tmp / "robot.toml"), str(tmp / "data.csv"), "--compensation", str(tmp / "c.csv")]) == 2


# ---------------------------------------------------------------------------------------------------------------
# 6-PSU: a located cause (<element>_in_legs)
# ---------------------------------------------------------------------------------------------------------------
def test_6psu_located_cause_round_trip(tmp_path):
    """Spherical joint 2-2.6x softer in two random legs: the corrected case ([model.leg_scale]) reproduces the fit's
    "after" readings and a diagnosis of it against the same data names nothing further."""
    import femcheck
    from femcheck.case.registry import load_case
    from femcheck.diagnose import AnalyticalChainModel, diagnose, predict_readings
    from femcheck.diagnose.extended_case import extended_case_text
    from femcheck.experiment.simulate import simulate
    from femcheck.measured import process
    case_path = "cases/haptic_6psu.toml"
    case = femcheck.load_case(case_path)
    rng = np.random.default_rng(37)
    legs = sorted(rng.choice(6, size=2, replace=False).tolist())
    truth = {f"leg{i}": float(rng.uniform(2.0, 2.6)) for i in legs}
    r = process(simulate(case, [("spherical_joint_in_legs", truth)], seed=int(rng.integers(1000)),
                         directions=("+x", "+y", "+z")).data, case)
    d = diagnose(AnalyticalChainModel(case, "detailed", "rigid"), r, with_baseline=False)
    assert [c.id for c in d.causes] == ["spherical_joint_in_legs"] and list(d.causes[0].legs) == legs
    out = tmp_path / "ext.toml"
    out.write_text(extended_case_text(case, open(case_path).read(), d, "detailed"))
    assert "[model.leg_scale]" in out.read_text() and "from spherical_joint_in_legs" in out.read_text()
    ext = load_case(out)
    m2 = AnalyticalChainModel(ext, "detailed", "rigid")
    diff = float(np.abs(predict_readings(m2, r) - d.fit.predicted).max())
    print(f"6-PSU round trip: largest prediction difference {diff:.3g} m (sigma {r.reading_sigma_m:.3g} m)")
    assert diff < 1e-6 * r.reading_sigma_m     # module docstring: rounding only
    d2 = diagnose(m2, r, with_baseline=False)
    assert d2.verdict == "none", (d2.verdict, [c.id for c in d2.causes])
    # the stiffness of the corrected device: the leg's spherical joint is softer, the others as modelled
    from femcheck.chain import evaluate
    S = evaluate(ext, r.pose[:1], np.zeros(6)).S[0]
    S0 = evaluate(case, r.pose[:1], np.zeros(6)).S[0]
    assert np.trace(S[:3, :3]) > np.trace(S0[:3, :3])
    # the worked example's last step: a stiffness map of the corrected device
    assert main(["map", str(out), "--direction", "z", "--resolution", "9", "--out", str(tmp_path / "map.png")]) == 0
    assert (tmp_path / "map.png").stat().st_size > 1000


def test_6psu_unwritable_cause_is_refused_by_name():
    """hertz_stiffening has no key in the case kind: refused by name (exit 2 through FemcheckError), not dropped."""
    import femcheck
    from femcheck.diagnose.effects import get_effect
    from femcheck.diagnose.extended_case import extended_case_text
    from femcheck.errors import FemcheckError
    case = femcheck.load_case("cases/haptic_6psu.toml")

    class Fit:
        effects = (get_effect("hertz_stiffening"),)
        values, ci_low, ci_high = ((3.0,),), ((2.0,),), ((4.0,),)

    class D:
        fit, causes = Fit(), ()
    with pytest.raises(FemcheckError, match="hertz_stiffening"):
        extended_case_text(case, open("cases/haptic_6psu.toml").read(), D(), "detailed")


# ---------------------------------------------------------------------------------------------------------------
# cobot identification (seed 002 extended VJM)
# ---------------------------------------------------------------------------------------------------------------
def test_cobot_identification_round_trip(tmp_path, capsys):
    """identify --extended-case: the written springs predict, at every measured pose and wrench, the fit's own
    deflections A c; its verification error is the one identify reported."""
    from femcheck.case.registry import load_case
    from femcheck.cli.identify import read_data
    from femcheck.vjm.extended_vjm import identification_matrix, virtual_jacobian
    from femcheck.vjm.serial_vjm import deflect
    data, out, js = tmp_path / "d.csv", tmp_path / "cobot_ext.toml", tmp_path / "i.json"
    assert main(["identify", "cases/cobot7.toml", str(data), "--make-data", "--noise", "0.001", "--seed", "3"]) == 0
    assert main(["identify", "cases/cobot7.toml", str(data), "--extended-case", str(out), "--json", str(js)]) == 0
    j = json.loads(js.read_text())
    ext = load_case(out)
    sets, q, W, dX = read_data(str(data), ext.n_joints)
    vjm = ext.vjm()
    J = virtual_jacobian(vjm.chain, q, True, vjm.tilt_offset_m)
    after = (identification_matrix(J, W) @ np.array(j["compliances"])).reshape(-1, 3)
    pred = deflect(vjm, q, W, complementary=False).twist[:, :3]
    diff = float(np.abs(pred - after).max())
    print(f"cobot round trip: largest prediction difference {diff:.3g} m (deflections up to {np.abs(dX).max():.3g} m)")
    # the fit's tolerance: least squares to machine precision on cond(A) ~ 2e2; 1e-9 of the largest deflection
    assert diff < 1e-9 * np.abs(dX).max()
    ver = sets == "verification"
    e = 100 * np.linalg.norm(pred[ver] - dX[ver], axis=1) / np.linalg.norm(dX[ver], axis=1)
    assert e.mean() == pytest.approx(j["error_verification_pct"]["mean"], rel=1e-6)
    assert "from identify extended VJM" in out.read_text()
    # OUT == CASE is refused before any work
    assert main(["identify", "cases/cobot7.toml", str(data), "--extended-case", "cases/cobot7.toml"]) == 2


# ---------------------------------------------------------------------------------------------------------------
# parallel device (general kind): an element kind softer in one leg
# ---------------------------------------------------------------------------------------------------------------
def test_parallel_device_round_trip(tmp_path):
    """Hexapod, one drive 2.5x softer: the corrected case's [model.element_scale] predicts the fit's "after"
    deflections, and diagnosing it against the same data moves no factor beyond the threshold."""
    from femcheck.case.registry import load_case
    from femcheck.measured.csv_format import read_measured_csv, write_measured_csv
    from femcheck.parallel.diagnosis import diagnose, predict, readings_from, simulate
    path = "cases/hexapod_6ups.toml"
    case = load_case(path)
    dev = case.device
    s = np.ones((dev.n_legs, len(dev.element_names)))
    s[3, dev.element_names.index("drive")] = 2.5
    csv, out, js = tmp_path / "m.csv", tmp_path / "ext.toml", tmp_path / "d.json"
    write_measured_csv(csv, *simulate(case, s, noise_m=2e-7), resolution_m=1e-7)
    assert main(["diagnose", path, str(csv), "--extended-case", str(out), "--json", str(js)]) == 0
    name = dev.legs[3].name
    assert "[model.element_scale]" in out.read_text() and f"drive in legs {name}" in out.read_text()
    ext = load_case(out)
    data = read_measured_csv(csv)
    best = json.loads(js.read_text())["best"]
    assert best["what"] == f"drive in legs {name}"
    fitted = np.ones_like(s)          # the kept candidate's factor, as the JSON reports it
    fitted[3, dev.element_names.index("drive")] = best["factors"]["drive"]
    rd = readings_from(case, data)
    joints = case.model.joint_rotations
    after = predict(case, rd, fitted, model="detailed", joints=joints)
    got = predict(ext, rd, np.ones_like(s), model="detailed", joints=joints)
    diff = float(np.abs(got - after).max())
    print(f"parallel device round trip: largest prediction difference {diff:.3g} m")
    assert diff < 1e-6 * 2e-7      # the same factors multiply the same compliances: rounding only (noise 2e-7 m)
    d2 = diagnose(ext, data)
    assert d2.effects == (), d2.effects


# ---------------------------------------------------------------------------------------------------------------
# HISS weights (seed 001)
# ---------------------------------------------------------------------------------------------------------------
def test_hiss_weights_round_trip(tmp_path):
    """identify --extended-case on a parallel_vjm case: [fitting] weights make the links' stiffness W K W, so the
    written case predicts the weight fit's twists with all weights 1."""
    from femcheck.case.registry import load_case
    from femcheck.vjm import hiss_pipeline as hp
    data_path, out, js = tmp_path / "h.csv", tmp_path / "hiss_ext.toml", tmp_path / "h.json"
    assert main(["identify", "cases/hiss.toml", str(data_path), "--make-data", "--seed", "1"]) == 0
    assert main(["identify", "cases/hiss.toml", str(data_path), "--restarts", "3", "--extended-case", str(out),
                 "--json", str(js)]) == 0
    g = json.loads(js.read_text())["setups"]["D/F + F/D"]
    case, ext = load_case("cases/hiss.toml"), load_case(out)
    assert list(ext.fitting.weights) == g["weights"]
    data = hp.read_csv(str(data_path), case)
    after = hp.model_for(case, data.point, data.wrench).predict(np.array(g["weights"]))
    got = hp.model_for(ext, data.point, data.wrench).predict(np.ones(case.fitting.n_weights))
    diff = float(np.abs(got - after).max())
    print(f"HISS round trip: largest twist difference {diff:.3g} (m / rad; noise 2e-5 m)")
    # the weights enter as the same diagonal products; cond(K_i) ~ 1e9 leaves rounding at ~1e-9 relative
    assert diff < 1e-6 * 2e-5


# ---------------------------------------------------------------------------------------------------------------
# every writable cause, without a diagnosis: the written keys reproduce the fitted effects
# ---------------------------------------------------------------------------------------------------------------
def _fit(effects, values):
    """A stand-in for a diagnosis' leading fit (effects at values, intervals +-10 %)."""
    class Fit:
        pass
    f = Fit()
    f.effects, f.values = tuple(effects), tuple(np.asarray(v, float) for v in values)
    f.ci_low, f.ci_high = tuple(0.9 * v for v in f.values), tuple(1.1 * v for v in f.values)

    class D:
        fit, causes = f, ()
    return D()


def test_6psu_every_writable_effect_round_trips(tmp_path):
    """Element scales (a located one, link modulus, leg softening), joint-rotation release, friction, clearance and
    the dial frame written into the case predict what the effects predict on the case as given (same chain, same
    effect code: rounding only)."""
    import femcheck
    from femcheck.case.registry import load_case
    from femcheck.diagnose import AnalyticalChainModel, predict_readings
    from femcheck.diagnose.effects import get_effect
    from femcheck.diagnose.extended_case import extended_case_text
    from femcheck.experiment.simulate import simulate
    from femcheck.measured import process
    case = femcheck.load_case("cases/haptic_6psu.toml")
    r = process(simulate(case, [], seed=3, directions=("+x", "+y", "+z")).data, case)
    effects = [get_effect("actuation_in_legs").restricted([2, 5]), get_effect("link_modulus"),
               get_effect("leg_softening"), get_effect("joint_rotation_release"), get_effect("friction_hysteresis"),
               get_effect("clearance"), get_effect("sensor_misalignment")]
    values = [[1.7, 2.2], [0.8], [1.0, 1.3, 1.0, 1.0, 1.0, 1.6], [0.05], [1.5], [2e-5, 0.0, 1e-5, 3.0],
              [0.02, -0.01, 0.03]]
    out = tmp_path / "all.toml"
    out.write_text(extended_case_text(case, open("cases/haptic_6psu.toml").read(), _fit(effects, values), "detailed"))
    ext = load_case(out)
    want = predict_readings(AnalyticalChainModel(case, "detailed", "rigid"), r, effects, values)
    got = predict_readings(AnalyticalChainModel(ext, "detailed", "rigid"), r)
    # rotation vector -> matrix -> rotation vector of the dial frame: 1e-15 relative; 1e-9 of the deflection is far below
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9 * np.abs(want).max())
    assert np.abs(got - predict_readings(AnalyticalChainModel(case, "detailed", "rigid"), r)).max() > 1e-6


def test_serial_every_spring_round_trips(tmp_path):
    """Torsion, tilt, backlash, link bending and mass scale as row keys: the corrected case's equilibrium equals the
    fitted elastic parameters' (same tree code; 1/(1/c) and the mass product round to 1e-16 relative)."""
    from femcheck.case.registry import load_case
    from femcheck.robot.corrected_case import corrected_case_edits, marker_positions
    from femcheck.robot.elastic import ElasticParams, equilibrium, flat_layout
    from femcheck.robot.measurement_model import NuisanceLayout
    from femcheck.robot.simulate import industrial_case, random_poses, to_toml
    from femcheck.case.toml_edit import edited
    case, raw = industrial_case(1, springs=True)
    tree = case.tree
    lay = flat_layout(tree)
    inc = np.zeros(lay["mass_scale"].stop)
    units = []
    for kind, unit, v in (("torsion", 1, 4e-5), ("tilt", 3, 2e-4), ("backlash", 2, 1e-3), ("bending", 2, 1e-6),
                          ("mass_scale", 0, 0.1)):
        inc[lay[kind].start + unit] = v
        units.append(({"torsion": "joint_torsion_compliance", "tilt": "joint_tilt_compliance", "backlash": "gear_clearance",
                       "bending": "link_bending_compliance", "mass_scale": "mass_scale"}[kind], kind, ((unit,),),
                      np.array([v]), np.array([0.1 * v]), 0.99))
    params = ElasticParams.nominal(tree).shifted(tree, inc)
    width = np.full(tree.n_joints, 3.0)

    class D:
        fitted = {"x": np.zeros(NuisanceLayout.of(tree, case.diagnosis).size), "params": params, "R": np.eye(3),
                  "t": np.zeros(3), "backlash_width": width, "units": units, "kept": np.zeros(0, int),
                  "nuisance_se": np.zeros(NuisanceLayout.of(tree, case.diagnosis).size)}
    text = to_toml(raw)
    out = tmp_path / "springs.toml"
    out.write_text(edited(text, corrected_case_edits(case, D()), "test"))
    ext = load_case(out)
    q = random_poses(tree, 20, np.random.default_rng(1))
    want = equilibrium(tree, q, None, params, case.diagnosis.fixed_point_passes, None, width).markers
    got = marker_positions(ext, q)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)    # m; deflections are ~1e-3 m
    assert "from gear_clearance" in out.read_text() and "mass scale" in out.read_text()
