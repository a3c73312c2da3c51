"""The beam-FE world of the cobot: closed forms, the VJM limits, and seed 002's outcome on it.

This world's joints are the extended model's own springs at its tilt places, with a bearing scale set to seed
002's torsion share: the extended model's fit is close to exact by construction, so these tests check the
assembly (world, identification, scoring). The test of the model is the bearings world
(tests/test_vjm_bearing_world.py).

Geometry caveat for every comparison with seed 002: the arm is the KUKA LBR iiwa 7 R800 (cases/cobot7.toml),
not the SHIR5, whose joint geometry the seed does not publish; the world is femcheck's beam model, not the
seed's solid FE model.
"""
from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

import femcheck
from femcheck.cli import main
from femcheck.vjm.beam_world import Bearing, BeamWorld, Tube, arm_mass_kg, cobot7_world, tcp_deflections
from femcheck.vjm.dh import DHChain
from femcheck.vjm.serial_vjm import deflect
from femcheck.vjm.world_identification import identify_on_world

ROOT = Path(__file__).resolve().parents[1]
TUBE = Tube(0.10, 0.004)
L = 0.4
RIGID = Bearing(torsion_Nm_per_rad=math.inf)


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case(ROOT / "cases" / "cobot7.toml")


@pytest.fixture(scope="module")
def table1(case):
    p = case.identification
    return np.radians(np.array(p.configurations_deg + p.verification_configurations_deg, dtype=float)), np.array(p.wrenches)


@pytest.fixture(scope="module")
def study(case):
    return identify_on_world(case, cobot7_world(case))


def _one_tube(bearing=RIGID, shear=True, max_element_m=0.05):
    """One joint; its body is a single tube of length L along x_1 (DH a = L) from the clamped joint (offset 0)."""
    chain = DHChain(a_m=(L,), alpha_rad=(0.0,), d_m=(0.0,), theta_offset_rad=(0.0,))
    return BeamWorld(chain=chain, bearings=(bearing,), links=(TUBE, TUBE), tool=TUBE, shear=shear,
                     max_element_m=max_element_m)


def test_straight_tube_cantilever_bending_and_torsion():
    """Tip force P normal to the tube: P L^3 / (3 E I) (Euler-Bernoulli) + P L / (kappa G A) (Timoshenko);
    tip torque T about the axis: T L / (G J). The element is nodally exact for end loads: round-off only."""
    q = np.radians([[35.0]])                                            # the tube lies along (cos 35, sin 35, 0)
    axis = np.array([np.cos(q[0, 0]), np.sin(q[0, 0]), 0.0])
    normal = np.array([-axis[1], axis[0], 0.0])
    P, T = 200.0, 30.0
    W = np.array([[*(P * normal), 0, 0, 0], [0, 0, P, 0, 0, 0], [0, 0, 0, *(T * axis)]])
    s = TUBE.section
    eb = P * L**3 / (3 * TUBE.E_Pa * s.Ix)
    d = tcp_deflections(_one_tube(shear=False), q, W).twist[0]
    assert d[0, :3] @ normal == pytest.approx(eb, rel=1e-10)
    assert d[1, 2] == pytest.approx(eb, rel=1e-10)
    assert d[2, 3:] @ axis == pytest.approx(T * L / (TUBE.G_Pa * s.J), rel=1e-10)
    d = tcp_deflections(_one_tube(), q, W).twist[0]
    assert d[0, :3] @ normal == pytest.approx(eb + P * L / (s.kappa_x * TUBE.G_Pa * s.A), rel=1e-10)


def test_joint_springs_act_in_series_with_the_tube():
    """The joint at the root: torsion k_t in series with the tube's G J / L; a radial force P at the tip
    adds P / k_r (radial) + P L^2 / k_tilt (the tilt lever) to P L^3 / (3 E I). Closed forms, round-off."""
    b = Bearing(torsion_Nm_per_rad=5e3, tilt_Nm_per_rad=4e4, radial_N_per_m=2e7, axial_N_per_m=3e7)
    q = np.zeros((1, 1))
    P, T = 100.0, 20.0
    W = np.array([[0, P, 0, 0, 0, 0], [P, 0, 0, 0, 0, 0], [0, 0, 0, T, 0, 0], [0, 0, P, 0, 0, 0]])
    d = tcp_deflections(_one_tube(b, shear=False), q, W).twist[0]
    s = TUBE.section
    # tube along x, joint axis z: y and x are radial, z is axial; the torsion spring levers a force along y
    assert d[0, 1] == pytest.approx(P * L**3 / (3 * TUBE.E_Pa * s.Ix) + P / b.radial_N_per_m + P * L**2 / b.torsion_Nm_per_rad, rel=1e-10)
    assert d[1, 0] == pytest.approx(P * L / (TUBE.E_Pa * s.A) + P / b.radial_N_per_m, rel=1e-10)
    assert d[2, 3] == pytest.approx(T * L / (TUBE.G_Pa * s.J) + T / b.tilt_Nm_per_rad, rel=1e-10)
    assert d[3, 2] == pytest.approx(P * L**3 / (3 * TUBE.E_Pa * s.Ix) + P / b.axial_N_per_m + P * L**2 / b.tilt_Nm_per_rad, rel=1e-10)


def test_self_weight_of_a_horizontal_tube():
    """Uniform load q = rho A g on a cantilever: tip deflection q L^4 / (8 E I). The weight is lumped half to
    each element node, which converges as h^2: 80 elements, 1e-3."""
    w = _one_tube(shear=False, max_element_m=L / 80)
    d = tcp_deflections(w, np.zeros((1, 1)), np.zeros((1, 6)), gravity=True)
    qload = TUBE.density_kg_m3 * TUBE.section.A * 9.81
    assert d.self_weight[0, 2] == pytest.approx(-qload * L**4 / (8 * TUBE.E_Pa * TUBE.section.Ix), rel=1e-3)
    np.testing.assert_allclose(d.twist[0, 0], d.self_weight[0])     # zero wrench: the self-weight alone


def test_rigid_links_and_torsion_only_joints_are_the_conventional_vjm(case, table1):
    """World with rigid links and bearings (only the drives' torsion): J K^-1 J^T F of femcheck's DH/VJM code,
    computed independently, on seed 002 Table I's 13 configurations x 2 wrenches, all six twist components."""
    q, W = table1
    world = cobot7_world(case).with_rigid_structure()
    got = tcp_deflections(world, q, W).twist
    vjm = case.vjm(extended=False)
    ref = np.stack([deflect(vjm, q, w, complementary=False, stiffness=False).twist for w in W], axis=1)
    assert np.abs(got - ref).max() <= 1e-8 * np.abs(ref).max()


def test_rigid_links_and_tilting_joints_are_the_extended_vjm(case, table1):
    """Rigid links, joints with torsion and tilt springs at the case's tilt_offset_m (translations rigid):
    the extended VJM (seed 002, tilt springs about the joint-frame x and y) to 1e-8."""
    q, W = table1
    bearings = tuple(Bearing(torsion_Nm_per_rad=j.torsional_stiffness, tilt_Nm_per_rad=j.tilt_stiffness_Nm_per_rad[0],
                             offset_m=j.tilt_offset_m) for j in case.joints)
    world = dataclasses.replace(cobot7_world(case), rigid_links=True, bearings=bearings)
    got = tcp_deflections(world, q, W).twist
    ref = np.stack([deflect(case.vjm(extended=True), q, w, complementary=False, stiffness=False).twist for w in W], axis=1)
    assert np.abs(got - ref).max() <= 1e-8 * np.abs(ref).max()


def test_cobot_world_is_a_7kg_class_arm(case):
    """The world's stated parameters: 24.3 kg in all (the iiwa 7 R800 weighs 23.9 kg); TCP deflections of a
    few mm under seed 002's load."""
    world = cobot7_world(case)
    d = tcp_deflections(world, np.zeros((1, 7)), np.zeros((1, 6)), gravity=True)
    assert d.n_dof[0] > 6 * 40                                          # a real mesh, not a lumped model
    assert arm_mass_kg(world) == pytest.approx(24.3, abs=0.05)
    # stretched upright (configuration 11) the weight is almost all axial: a fraction of a mm at the TCP
    assert 1e3 * np.linalg.norm(d.self_weight[0, :3]) < 0.5


def test_extended_model_beats_the_conventional_one_on_the_world(study):
    """Seed 002's qualitative outcome. Measured (noise-free, Table I, 26 tests): conventional 8.98 % mean,
    extended 0.08 % mean; verification 9-13: 14.43 % vs 0.14 %. Issue 21's target is extended <= 0.5 x
    conventional (the seed's ratio is 0.48); the margin here is 50x, so 0.5 is a loose bound on purpose."""
    conv, ext = (study.summary(study.fits[k]) for k in ("conventional", "extended"))
    assert ext["table1_all"]["mean"] <= 0.5 * conv["table1_all"]["mean"]
    assert ext["verification"]["mean"] <= 0.5 * conv["verification"]["mean"]
    assert ext["verification"]["max"] < conv["verification"]["max"]
    # the pinned figures (a change of the world must update the docs): 2 decimals, as printed
    assert (round(conv["table1_all"]["mean"], 2), round(ext["table1_all"]["mean"], 2)) == (8.98, 0.08)


def test_with_measurement_noise_the_outcome_holds(case):
    """0.02 mm noise (laser-tracker class) on deflections of 1.3-7.3 mm. The figures depend on the draw; two draws
    are quoted, both from numpy default_rng(0) (``--seed 0``), mean over the 26 Table I tests:
    * no random poses (this test): conventional 9.23 %, extended 1.07 %;
    * ``--random-poses 20`` (the docs' example): conventional 8.91 %, extended 1.10 %; the 20 poses are drawn
      first from the same generator, so the noise on the Table I tests is another draw.
    The ratio stays below 0.5 in both."""
    for poses, quoted in ((0, (9.23, 1.07)), (20, (8.91, 1.10))):
        st = identify_on_world(case, cobot7_world(case), noise_mm=0.02, seed=0, random_poses=poses)
        conv, ext = (st.summary(st.fits[k]) for k in ("conventional", "extended"))
        assert ext["table1_all"]["mean"] <= 0.5 * conv["table1_all"]["mean"]
        # the quoted figures are this draw's, as printed (2 decimals)
        assert (round(conv["table1_all"]["mean"], 2), round(ext["table1_all"]["mean"], 2)) == quoted


def test_what_of_the_published_numbers_compares(study):
    """Seed 002 (SHIR5, its own FE) vs this world (iiwa geometry, beam FE):
    * torsion share 76.5 % on average: the world's one free scale (the bearings' effective stiffness) was set
      to it, so this pins the calibration (77.5 %), it does not confirm the paper: within 2 points;
    * the conventional model's mean error, 7.75 %: the world gives 8.98 %, the same order: within a factor 1.5
      (an independent outcome; the geometry differs, so no closer agreement is expected);
    * the extended model's 3.74 % and verification max 10.9 % are NOT reproduced: the beam world is almost
      exactly lumpable into torsion + tilt springs (0.08 %, max 0.31 %); the seed's solid model holds
      compliance that no 21 springs capture. This test records that finding."""
    share = 100 * study.world_torsion_share[:13, 0]
    assert abs(share.mean() - 76.5) < 2.0
    conv, ext = (study.summary(study.fits[k]) for k in ("conventional", "extended"))
    assert 7.75 / 1.5 < conv["table1_all"]["mean"] < 7.75 * 1.5
    assert ext["table1_all"]["mean"] < 3.74 and ext["verification"]["max"] < 10.9


def test_identified_torsion_stiffness_is_closer_to_the_drives_with_the_extended_model(case, study):
    """The conventional model lumps the bearings' tilt into the torsion springs, so it identifies them too soft;
    the extended model's torsion springs come out within 10 % of the world's drives (measured: 0.2-4 %), the
    conventional ones 12-35 % too soft (noise-free, Table I 1-8)."""
    k_world = np.array([j.torsional_stiffness for j in case.joints])
    k_ext = 1 / study.fits["extended"].compliance[0::3]
    k_conv = 1 / study.fits["conventional"].compliance
    assert np.all(np.abs(k_ext / k_world - 1) < 0.10)
    assert np.all(k_conv < k_world) and np.all(np.abs(k_ext / k_world - 1) < np.abs(k_conv / k_world - 1))


def test_identify_world_cli_json_and_text(tmp_path, capsys):
    out = tmp_path / "w.json"
    assert main(["identify", "cases/cobot7.toml", "--world", "beam", "--random-poses", "3", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "KUKA LBR iiwa 7 R800" in text and "7.75" in text and "3.74" in text
    res = json.loads(out.read_text())
    assert set(res["models"]) == {"conventional", "extended"}
    assert len(res["configurations"]) == 13 + 3
    for m in res["models"].values():
        assert {"compliances", "compliances_ci", "cond_A", "error_identification_pct", "error_verification_pct",
                "error_random_pct", "error_table1_pct", "torsion_share"} <= set(m)
        assert len(m["compliances"]) in (7, 21)
        assert m["error_norm_table1_pct"]["mean"] <= m["error_table1_pct"]["mean"]   # ||a| - |b|| <= |a - b|
    assert res["models"]["extended"]["error_table1_pct"]["mean"] == pytest.approx(0.08, abs=0.005)


def test_world_data_through_the_csv_path_gives_the_same_fit(tmp_path, capsys, study):
    """--make-data --world beam writes the world's measurements as DATA.csv; `identify` on it gives the
    identified compliances of the --world run (the same least squares on the same numbers)."""
    path = tmp_path / "w.csv"
    assert main(["identify", "cases/cobot7.toml", str(path), "--make-data", "--world", "beam"]) == 0
    assert main(["identify", "cases/cobot7.toml", str(path), "--model", "extended", "--json", "-"]) == 0
    res = json.loads(capsys.readouterr().out.split("\n", 1)[1])
    np.testing.assert_allclose(res["compliances"], study.fits["extended"].compliance, rtol=1e-9)


@pytest.mark.parametrize("args,culprit", [
    (["--world", "solid"], "--world"),
    (["--world", "beam", "--noise-mm", "-1"], "--noise-mm"),
    (["--world", "beam", "--random-poses", "-2"], "--random-poses"),
    (["x.csv", "--world", "beam"], "x.csv"),
    ([], "DATA.csv"),
])
def test_bad_world_options_exit_2(capsys, args, culprit):
    assert main(["identify", "cases/cobot7.toml", *args]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and culprit in err[0]


def test_docs_quote_the_world_run(study):
    """docs/vjm.md quotes the headline of `femcheck identify cases/cobot7.toml --world beam`: it must be this run's."""
    text = (ROOT / "docs" / "vjm.md").read_text()
    conv, ext = (study.summary(study.fits[k]) for k in ("conventional", "extended"))
    line = (f"all Table I tests      conventional {conv['table1_all']['mean']:.2f} % mean / {conv['table1_all']['max']:.2f} % max; "
            f"extended {ext['table1_all']['mean']:.2f} % mean / {ext['table1_all']['max']:.2f} % max")
    assert line in text
    assert re.search(r"verification \(9-13\)\s+conventional " + re.escape(f"{conv['verification']['mean']:.2f}"), text)
