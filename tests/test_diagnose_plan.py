"""``femcheck plan``: candidate poses, the separation criterion checked against a full refit, and
an ambiguous pair that the plan resolves and the same number of random cube measurements does not."""
import dataclasses
import json

import numpy as np
import pytest
from scipy.optimize import least_squares

import femcheck
from femcheck.cli import main
from femcheck.diagnose import AnalyticalChainModel, diagnose, predict_readings
from femcheck.diagnose.effects import get_effect
from femcheck.diagnose.evidence import AMBIGUITY_RATIO
from femcheck.diagnose.fitting import fit_effects
from femcheck.diagnose.plan import (candidate_poses, measurement_states, plan_measurements, read_pose_table,
                                    separation, unit_directions)
from femcheck.experiment.simulate import simulate
from femcheck.kinematics.conditioning import pose_conditioning
from femcheck.kinematics.directions import direction_unit
from femcheck.kinematics.psu6 import leg_geometry, test_points as cube_points
from femcheck.measured import process
from femcheck.measured.csv_format import concat_measured, format_measured_csv

CASE = "cases/haptic_6psu.toml"
#: the ambiguous pair: both one-parameter (the BIC does not favour either by its parameter count); at P0 and P6
#: under +z alone a 7 % softer drive and softer joints fit equally well (posteriors ~0.6 / ~0.5)
# 10 % softer actuation: at 2 points and +z the readings cannot tell it from a softer joint contact; 7 % was used while
# the reading sigma was pooled over axes that read zero throughout (hidden scatter, sigma too small): at the trial
# scatter of the axes that read, 7 % leaves "none" leading and nothing to plan for
TRUTH = ("actuation_compliance", {"scale": 1.10})
RIVAL = "joint_contact_compliance"
POOL = [TRUTH[0], RIVAL]
SPARSE_POINTS = ["P0", "P6"]
BUDGET = 2
TOP_LOAD_N = 30.0      # the plan's highest load level (2 x the 15 N test load); the random measurements get it too


def _subset(data, points):
    keep = np.isin(data.point, points)
    return dataclasses.replace(data, **{f: getattr(data, f)[keep] for f in
                                        ("point", "direction", "trial", "phase", "load_N", "force", "disp", "row")})


def _cause_probability(d, cause):
    """Marginal posterior of ``cause``: the sum over the explanations that contain it."""
    w = d.weighing
    return float(sum(p for e, p in zip(w.explanations, w.probability) if cause in e.ids))


@pytest.fixture(scope="module")
def setting():
    case = femcheck.load_case(CASE)
    model = AnalyticalChainModel(case, "detailed", "rigid")
    sparse = _subset(simulate(case, [TRUTH], seed=7, directions=("+z",), sweep=False).data, SPARSE_POINTS)
    readings = process(sparse, case)
    d = diagnose(model, readings, candidates=POOL, with_baseline=False)
    plan = plan_measurements(model, readings, d.weighing, budget=BUDGET)
    return case, model, sparse, readings, d, plan


def test_candidate_poses_are_reachable_well_conditioned_and_leave_the_cube():
    case = femcheck.load_case(CASE)
    c = candidate_poses(case, 60, seed=1)
    assert c.ids[:9] == tuple(f"P{k}" for k in range(9)) and len(c.ids) == 69
    legs = leg_geometry(case, c.poses)                     # raises if any pose is unreachable
    cond = pose_conditioning(case, legs).cond
    assert np.allclose(cond, c.cond) and np.all(cond <= 10.0)
    cube = cube_points(case)
    outside = np.any(np.abs(c.poses[9:, :3] - cube[0, :3]) > 0.5 * case.workspace.cube_edge_m + 1e-9, axis=1)
    assert outside.mean() > 0.5                            # most candidates lie outside the test cube
    # tilted poses (reach and conditioning checked above): up to 10 deg about each axis, spread over the range
    tilt = np.rad2deg(np.abs(c.poses[9:, 3:] - cube[0, 3:]))
    assert tilt.max() <= 10.0 + 1e-9 and np.mean(tilt.max(axis=1) > 3.0) > 0.5
    flat = candidate_poses(case, 20, seed=1, tilt_rad=0.0)
    assert np.allclose(flat.poses[:, 3:], cube[0, 3:])      # tilt 0: the case's orientation only
    U, labels = unit_directions()
    assert U.shape == (26, 3) and np.allclose(np.linalg.norm(U, axis=1), 1.0)
    assert set(labels[:6]) == {"+x", "-x", "+y", "-y", "+z", "-z"} and len(set(labels)) == 26


def test_separation_matches_a_full_refit_of_the_rival(setting):
    """The criterion two ways: the linearized refit D of the plan against a nonlinear least-squares refit of the
    rival to the old readings plus noiseless readings of the truth at one candidate measurement."""
    case, model, _, readings, _, plan = setting
    fit_t = fit_effects(model, readings, [get_effect(TRUTH[0])])
    fit_r = fit_effects(model, readings, [get_effect(RIVAL)])
    sigma = readings.reading_sigma_m / np.sqrt(3)
    # the plan's two measurements (large D) and two cube ones (small D)
    U, _ = unit_directions()
    poses = np.vstack([[m.pose for m in plan.measurements], cube_points(case)[[2, 6]]])
    units = np.vstack([[m.direction for m in plan.measurements], U[[0, 20]]])
    states = measurement_states(poses, units, np.full(4, TOP_LOAD_N), 5.0)
    D = separation(model, readings, fit_t, fit_r, states, sigma)
    d_true = predict_readings(model, states, fit_t.effects, fit_t.values)
    p = get_effect(RIVAL).params[0]
    for c in range(4):
        sl = slice(4 * c, 4 * c + 4)
        sub = dataclasses.replace(states, pose=states.pose[sl], force=states.force[sl], load_N=states.load_N[sl],
                                  peak_N=states.peak_N[sl], phase=states.phase[sl], case_index=np.zeros(4, int),
                                  case_unit=states.case_unit[c:c + 1])

        def res(x):
            v = [np.atleast_1d(p.from_x(x[0]))]
            old = (predict_readings(model, readings, fit_r.effects, v) - readings.disp) / readings.sigma
            new = (predict_readings(model, sub, fit_r.effects, v) - d_true[sl]) / sigma
            return np.concatenate([old.ravel(), new.ravel()])

        sol = least_squares(res, [p.to_x(fit_r.values[0][0])], method="lm")
        full = 2.0 * sol.cost - fit_r.chi2
        # the rival's predictions are nearly linear in its scale over the refit step: 5 % (or 0.5 in chi^2) covers it
        assert D[c] == pytest.approx(full, rel=0.05, abs=0.5), (c, D[c], full)


def test_plan_resolves_an_ambiguous_pair_that_random_cube_measurements_do_not(setting):
    case, model, sparse, readings, d, plan = setting
    # the pair is not separable with the sparse data: posterior ratio of the two single causes below the
    # weighing's ambiguity ratio (3)
    w = d.weighing
    single = {e.ids: p for e, p in zip(w.explanations, w.probability) if len(e.ids) == 1}
    ratio = single[(TRUTH[0],)] / single[(RIVAL,)]
    assert 1 / AMBIGUITY_RATIO < ratio < AMBIGUITY_RATIO, ratio
    before = _cause_probability(d, TRUTH[0])
    assert 0.3 < before < 0.8
    assert len(plan.measurements) == BUDGET and plan.n_candidate_poses > 9
    assert max(plan.expected_cause_probability_leader.values()) > 0.95
    # follow the plan: readings of the true world at the planned poses, directions and loads
    follow = simulate(case, [TRUTH], seed=107, rows=plan.protocol_rows(), pose_table=plan.pose_table())
    after = diagnose(model, process(concat_measured(sparse, follow.data), case, plan.pose_table()),
                     candidates=POOL, with_baseline=False)
    p_plan = _cause_probability(after, TRUTH[0])
    assert p_plan > 0.9, p_plan
    # the same number of random cube measurements (points P0..P8, axis directions, the same top load), 5 draws
    rng = np.random.default_rng(7)
    random_p = []
    for draw in range(5):
        picks = [(f"P{rng.integers(9)}", ("+x", "-x", "+y", "-y", "+z", "-z")[rng.integers(6)]) for _ in range(BUDGET)]
        rows = [(pt, f"rand{k + 1}", t, ph, load, load * direction_unit(dr))
                for t in (1, 2, 3) for k, (pt, dr) in enumerate(picks)
                for ph, load in (("preload", 5.0), ("total", 5.0 + TOP_LOAD_N), ("unload", 5.0), ("unload", 0.0))]
        cols = list(zip(*rows))
        rr = (np.array(cols[0], dtype=object), np.array(cols[1], dtype=object), np.array(cols[2], int),
              np.array(cols[3], dtype=object), np.array(cols[4], float), np.array(cols[5], float))
        extra = simulate(case, [TRUTH], seed=370 + draw, rows=rr)
        dd = diagnose(model, process(concat_measured(sparse, extra.data), case), candidates=POOL, with_baseline=False)
        random_p.append(_cause_probability(dd, TRUTH[0]))
    # a single random draw can be lucky (measured over 8 data seeds x 5 draws: 11 of 40 reached 0.9, the plan 8 of 8
    # with >= 0.93): the median of five draws stays below 0.9 (it did for 7 of the 8 data seeds)
    assert np.median(random_p) < 0.9 < p_plan, (random_p, p_plan)


def test_plan_cli_json_and_bad_input(setting, tmp_path, capsys):
    _, _, sparse, _, _, _ = setting
    csv = tmp_path / "sparse.csv"
    csv.write_text(format_measured_csv(sparse.point, sparse.direction, sparse.trial, sparse.phase, sparse.load_N,
                                       sparse.force, sparse.disp))
    out = tmp_path / "plan.json"
    assert main(["plan", CASE, str(csv), "--budget", "2", "--effects", ",".join(POOL), "--poses", "40",
                 "--json", str(out)]) == 0
    j = json.loads(out.read_text())
    assert len(j["measurements"]) == 2 and j["moments"] is False
    m = j["measurements"][0]
    assert set(m) >= {"pose_id", "x_mm", "y_mm", "z_mm", "direction", "ux", "uy", "uz", "load_N"}
    assert {"criterion", "criterion_value", "expected_posterior_leader", "expected_cause_probability_leader",
            "rivals", "plan_wall_s", "verdict"} <= set(j)
    # carry the plan out (simulated) and diagnose the joined readings with the plan's JSON as the pose table
    case = femcheck.load_case(CASE)
    table = read_pose_table(out, case)
    rows = [(mm["pose_id"], f"plan{k + 1}", t, ph, load, load * np.array([mm["ux"], mm["uy"], mm["uz"]]))
            for t in (1, 2, 3) for k, mm in enumerate(j["measurements"])
            for ph, load in (("preload", 5.0), ("total", 5.0 + mm["load_N"]), ("unload", 5.0), ("unload", 0.0))]
    cols = list(zip(*rows))
    follow = simulate(case, [TRUTH], seed=11, rows=(np.array(cols[0], dtype=object), np.array(cols[1], dtype=object),
                                                    np.array(cols[2], int), np.array(cols[3], dtype=object),
                                                    np.array(cols[4], float), np.array(cols[5], float)),
                      pose_table=table).data
    both = concat_measured(sparse, follow)
    joined = tmp_path / "joined.csv"
    joined.write_text(format_measured_csv(both.point, both.direction, both.trial, both.phase, both.load_N, both.force,
                                          both.disp))
    off_cube = [mm["pose_id"] for mm in j["measurements"] if not mm["pose_id"].startswith("P")]
    if off_cube:
        assert main(["diagnose", CASE, str(joined)]) == 2           # an off-cube id without its pose table
        assert off_cube[0] in capsys.readouterr().err
    dj = tmp_path / "d.json"
    assert main(["diagnose", CASE, str(joined), "--pose-table", str(out), "--json", str(dj)]) == 0
    assert json.loads(dj.read_text())["residual"]["n_data"] == 3 * 4 * (len(SPARSE_POINTS) + BUDGET)
    assert main(["plan", CASE, str(csv), "--effects", "no_such_effect"]) == 2
    assert main(["plan", CASE, str(csv), "--tilt-deg", "-3"]) == 2          # a negative tilt range
    assert main(["plan", CASE, str(csv), "--tilt-deg", "nan"]) == 2
    assert "no_such_effect" in capsys.readouterr().err
    assert main(["plan", CASE, str(tmp_path / "missing.csv")]) == 2
    assert main(["plan", CASE, str(csv), "--json", str(csv)]) == 2
    bad = tmp_path / "bad_plan.json"
    bad.write_text('{"measurements": [{"pose_id": "Q1", "x_mm": 400, "y_mm": 0, "z_mm": 375}]}')
    assert main(["diagnose", CASE, str(joined), "--pose-table", str(bad)]) == 2
    assert "unreachable" in capsys.readouterr().err
