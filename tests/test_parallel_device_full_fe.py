"""The device FE of parallel devices on its own laws: drive elements, contact-FE joints, coverage.

Fast tests use the drive elements and the closed-form joints (no contact FE); the contact-FE joint laws are
measured (or read from the on-disk cache) in the tests marked slow.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from femcheck.case import load_case
from femcheck.cli import get_app
from tests.conftest import ROOT

runner = CliRunner()
HEXAPOD, DELTA = ROOT / "cases" / "hexapod_6ups.toml", ROOT / "cases" / "delta_3ruu.toml"


def _drive(path):
    case = load_case(path)
    return next(j.drive for j in case.legs[0].joints if j.drive is not None)


@pytest.mark.parametrize("path", [HEXAPOD, DELTA], ids=["axial", "torsional"])
def test_drive_elements_condense_to_the_series_springs(path):
    """The condensed shaft + gearbox (+ capstan + strand) elements against the series springs written here:
    axial 1 / (l / (E pi d^2 / 4) + r^2 / (n^2 G pi D^4 / 32 / L)), torsional n^2 G pi D^4 / 32 / L. Both are
    exact for these elements (a truss and a torsion bar), so 1e-12 (round-off of the Schur complement)."""
    from femcheck.parallel.drive_fe import drive_stiffness
    d = _drive(path)
    k_shaft = d.shaft_G_Pa * math.pi * d.shaft_diameter_m**4 / 32.0 / d.shaft_length_m * d.gear_ratio**2
    if d.law == "axial":
        k_cable = d.cable_modulus_Pa * math.pi * d.cable_diameter_m**2 / 4.0 / d.cable_length_m
        expected = 1.0 / (1.0 / k_cable + d.capstan_radius_m**2 / k_shaft)
    else:
        expected = k_shaft
    assert drive_stiffness(d) == pytest.approx(expected, rel=1e-12)


def test_drive_elements_do_not_read_the_drive_law(monkeypatch):
    """A mistake put into the analytical drive law (the cable term x 3) moves the case's drive compliance, not the
    FE's drive elements."""
    import femcheck.compliance.actuation as act
    from femcheck.parallel.drive_fe import drive_stiffness
    d = _drive(HEXAPOD)
    k0, c0 = drive_stiffness(d), d.compliance
    real = act.cable_stiffness
    monkeypatch.setattr(act, "cable_stiffness", lambda *a: real(*a) / 3.0)
    assert d.compliance > 1.5 * c0          # the law moved
    assert drive_stiffness(d) == k0         # the elements did not


@pytest.fixture(scope="module")
def delta_closed_joints():
    """Delta coverage with the drive elements and the closed-form joints (no contact FE)."""
    from femcheck.coverage.device_coverage import device_coverage
    from femcheck.parallel.beam_fe import fe_laws_of
    case = load_case(DELTA)
    return case, device_coverage(case, fe_laws=fe_laws_of(case, joint_fe=False))


def test_delta_coverage_links_and_drive_own_joints_shared(delta_closed_joints):
    """The links (beam elements, not the cantilever law) and the drive (elements) are the FE's own: the FE does not
    move with their mutation (response ratio ~0); the closed-form U joints are the same law on both sides (ratio 1,
    never counted as caught). The links carry > 90 % of the Delta's compliance, so the covered share is >= 90 %."""
    _, res = delta_closed_joints
    rows = {e.element: e for e in res.elements}
    assert res.base_passes and res.base_error_pct < 1.0     # beam FE = chain algebra to round-off; drive exact
    for name in ("crank", "rod"):
        assert rows[name].fe_source == "beam_elements" and rows[name].fe_response_ratio < 1e-9
        assert rows[name].detected
    assert rows["drive"].fe_source == "elements" and rows["drive"].fe_response_ratio < 1e-9
    assert rows["hertz_line"].fe_source == "shared_closed_form" and not rows["hertz_line"].detected
    assert rows["hertz_line"].fe_response_ratio == pytest.approx(1.0, abs=0.02)   # the same law on both sides
    assert sum(e.share_pct for e in res.elements) == pytest.approx(100.0, abs=1e-6)
    assert res.covered_share_pct >= 90.0


def test_coverage_keeps_its_min_detectable_claim(delta_closed_joints):
    """What coverage claims it would catch, it catches: a mutation of the crank 25 % above its min_detectable_pct
    fails the check, one 25 % below passes (the error is linear in the law's compliance to within that margin)."""
    from femcheck.coverage.device_coverage import device_coverage
    from femcheck.parallel.beam_fe import fe_laws_of
    case, res = delta_closed_joints
    m = next(e for e in res.elements if e.element == "crank").min_detectable_pct
    laws = fe_laws_of(case, joint_fe=False)
    above = device_coverage(case, mutation_pct=1.25 * m, fe_laws=laws)
    below = device_coverage(case, mutation_pct=0.75 * m, fe_laws=laws)
    assert next(e for e in above.elements if e.element == "crank").detected
    assert not next(e for e in below.elements if e.element == "crank").detected


def test_without_drive_elements_the_drive_is_shared():
    """With the FE taking the drive law as it is (no elements), the hexapod's drive (~97 % of its compliance) moves
    both sides alike: it is not covered, and the covered share falls below 5 %."""
    from femcheck.coverage.device_coverage import device_coverage
    res = device_coverage(load_case(HEXAPOD), fe_laws=None)
    drive = next(e for e in res.elements if e.element == "drive")
    assert drive.fe_source == "shared_closed_form" and not drive.detected and drive.share_pct > 90.0
    assert res.covered_share_pct < 5.0


def test_coverage_cli_parallel_device_json(tmp_path):
    out = tmp_path / "cov.json"
    res = runner.invoke(get_app(), ["coverage", str(HEXAPOD), "--no-joint-fe", "--json", str(out)])
    assert res.exit_code == 0, res.output
    obj = json.loads(out.read_text())
    assert obj["covered_share_pct"] >= 90.0 and obj["base_passes"]
    assert [e["element"] for e in obj["elements"]] == ["strut", "drive", "hertz_point", "hertz_line"]
    bad = runner.invoke(get_app(), ["coverage", str(HEXAPOD), "--no-joint-fe", "--parts", "shell"])
    assert bad.exit_code == 2 and "--parts" in bad.output


# ---- contact-FE joint laws (measured once, then cached on disk) ----------------------------------------

@pytest.fixture(scope="module")
def hexapod_laws():
    from femcheck.parallel.beam_fe import fe_laws_of
    case = load_case(HEXAPOD)
    return case, fe_laws_of(case, joint_fe=True)


@pytest.mark.slow
def test_ball_in_seat_law_against_hertz(hexapod_laws):
    """The hexapod's steel ball on its steel seat, contact FE at the coarse level, against Hertz (Johnson eq. 4.23):
    approach within 3 % over the ladder (coarse mesh: 2.4 % at 1 N, < 1 % above 2 N measured) and the axial stick
    tangent within 8 % of the Hertz tangent 3 F / (2 delta) (measured 2-6 %: the stick area slightly stiffer)."""
    from femcheck.fe_device.contact_scales import device_springs
    from femcheck.fe_device.loads import hertz_approach
    from femcheck.parallel.joint_specimen import device_joints
    case, laws = hexapod_laws
    joint = next(j for j in device_joints(case) if j.kind == "spherical")
    law = laws.joints[joint.leg, joint.joint][1]
    sp = device_springs(joint.specimen)
    F = law.loads_N
    d_h = hertz_approach(F, sp.E_star_sp, sp.R_star_sp)
    np.testing.assert_allclose(law.approach_m, d_h, rtol=0.03)
    k = np.array([law.component_stiffness(f)[2] for f in F])
    np.testing.assert_allclose(k, 1.5 * F / d_h, rtol=0.08)


@pytest.mark.slow
def test_pin_in_bore_law_between_line_contact_and_the_simply_supported_pin(hexapod_laws):
    """The U joint's cross in its yokes, axial: stiffer than the pin simply supported over the whole span in series
    with the line contact (1 / (c_uc + c_ub): the hub and the bores shorten the free pin), softer than the Hertz
    line contact alone (K_uc = pi l E* / 2: the pin bends, the yokes deform). Measured 1.0e8 N/m in
    [6.9e7, 1.1e9]."""
    from femcheck.fe_device.contact_scales import device_springs
    from femcheck.parallel.joint_specimen import device_joints
    case, laws = hexapod_laws
    joint = next(j for j in device_joints(case) if j.kind == "universal")
    law = laws.joints[joint.leg, joint.joint][1]
    sp = device_springs(joint.specimen)
    k = np.array([law.component_stiffness(f)[2] for f in law.loads_N])
    assert np.all(k > 1.0 / (sp.c_uc + sp.c_ub)) and np.all(k < 1.0 / sp.c_uc)


@pytest.mark.slow
@pytest.mark.parametrize("path", [HEXAPOD, DELTA], ids=["hexapod", "delta"])
def test_coverage_with_contact_fe_joints_reaches_90_pct(path):
    """`femcheck coverage` with the joints' contact FE (the default): the joints are the FE's own (contact_fe, the
    FE does not move with their law), the base pair passes, and >= 90 % of the compliance is covered."""
    res = runner.invoke(get_app(), ["coverage", str(path), "--json", "-"])
    assert res.exit_code == 0, res.output
    obj = json.loads(res.output[res.output.index("{"):])
    rows = {e["element"]: e for e in obj["elements"]}
    assert rows["hertz_line"]["fe_source"] == "contact_fe" and rows["hertz_line"]["fe_response_ratio"] < 1e-9
    assert obj["fe_joints"] == "contact_fe" and obj["base_passes"]
    assert obj["covered_share_pct"] >= 90.0


@pytest.mark.slow
def test_contact_fe_joints_sit_at_the_statics_leg_force(hexapod_laws):
    """The hexapod's struts are two-force members, so each joint carries the leg force of the released-joint
    statics and only the joints' axial springs count. The FE with the contact-FE laws (at the force it finds by its
    fixed point) must equal the chain model whose joint compliances are scaled to those laws at the statics force
    (ball: Hertz tangent -> K_zz(F); pins: c_uc + c_ub -> 1 / K_zz(F)): the beam FE reproduces the chain algebra, so
    1e-7 (a joint at a wrong force or along a wrong axis is off by percents)."""
    from femcheck.kinematics.directions import direction_unit
    from femcheck.kinematics.points import test_poses
    from femcheck.parallel.beam_fe import device_fe_stiffness
    from femcheck.parallel.chain_model import evaluate
    case, laws = hexapod_laws
    dev = case.device
    P = test_poses(case, ("P0", "P3", "P6"))
    names = dev.element_names
    for d in ("+x", "+z"):
        W = np.concatenate([case.loads.test_N * direction_unit(d), np.zeros(3)])
        r0 = evaluate(dev, P, W, model="detailed", joints="released")
        scale = np.ones((len(P), dev.n_legs, len(names)))
        for i, leg in enumerate(dev.legs):
            F = np.linalg.norm(r0.leg_wrench[:, i, :3], axis=1)
            k_ball = np.array([laws.joints[leg.case_index, 2][1].component_stiffness(f)[2] for f in F])
            k_pins = np.array([laws.joints[leg.case_index, 0][1].component_stiffness(f)[2] for f in F])
            c_uc, c_ub, _ = leg.hertz_line[0]
            scale[:, i, names.index("hertz_point")] = r0.hertz_stiffness[i, 2] / k_ball
            scale[:, i, names.index("hertz_line")] = 1.0 / (k_pins * (c_uc + c_ub))
        r1 = evaluate(dev, P, W, model="detailed", joints="released", element_scale=scale)
        K = device_fe_stiffness(dev, P, fe_laws=laws, wrench=W, hertz_stiffness=r0.hertz_stiffness)
        t = np.linalg.solve(K, np.broadcast_to(W, (len(P), 6))[..., None])[..., 0]
        np.testing.assert_allclose(t[:, :3], r1.twist[:, :3], rtol=1e-7, atol=1e-7 * np.abs(r1.twist[:, :3]).max())


@pytest.mark.parametrize("joint_fe", [False, pytest.param(True, marks=pytest.mark.slow)], ids=["closed-joints", "contact-fe"])
def test_diagnose_names_a_hidden_drive_change_in_an_fe_world(joint_fe, tmp_path):
    """A virtual hexapod measured by its device FE (beam links, the joints' contact FE or their closed forms, each
    drive a spring of the case's drive compliance, which its elements reproduce to 1e-16, leg b2's doubled),
    0.2 um dial noise: diagnose keeps `drive in legs b2`, cause drive_in_legs, factor 2 within
    3 % (the FE and the model differ by 0.1-0.2 % unmutated) and its 95 % interval holds 2 within that margin.
    Closed-form joints: the kept candidate is `drive in legs b2` (one factor)."""
    import dataclasses

    from femcheck.kinematics.directions import direction_unit
    from femcheck.kinematics.points import test_poses
    from femcheck.measured.csv_format import write_measured_csv
    from femcheck.parallel.beam_fe import FeLaws, device_fe_stiffness, fe_laws_of
    from femcheck.parallel.chain_model import evaluate
    from femcheck.parallel.diagnosis import simulate
    case = load_case(HEXAPOD)
    dev = case.device
    laws = fe_laws_of(case, joint_fe=joint_fe)
    legs = list(dev.legs)
    legs[3] = dataclasses.replace(legs[3], drive_compliance=2.0 * legs[3].drive_compliance)
    world = dataclasses.replace(dev, legs=tuple(legs))
    P = test_poses(case)
    rows = simulate(case, np.ones((dev.n_legs, len(dev.element_names))))   # the CSV layout: point-major, then direction
    disp = np.empty((len(P), len(case.loads.directions), 3))
    for j, d in enumerate(case.loads.directions):
        W = np.concatenate([case.loads.test_N * direction_unit(d), np.zeros(3)])
        hz = evaluate(dev, P, W, model="detailed", joints="released").hertz_stiffness
        K = device_fe_stiffness(world, P, fe_laws=FeLaws(joints=laws.joints), wrench=W, hertz_stiffness=hz)
        disp[:, j] = np.linalg.solve(K, np.broadcast_to(W, (len(P), 6))[..., None])[:, :3, 0]
    noise = np.random.default_rng(7).normal(0.0, 2e-7, disp.shape)
    csv = tmp_path / "fe_world.csv"
    write_measured_csv(csv, *rows[:-1], (disp + noise).reshape(-1, 3), resolution_m=1e-7)
    res = runner.invoke(get_app(), ["diagnose", str(HEXAPOD), str(csv), "--json", "-"])
    assert res.exit_code == 0, res.output
    obj = json.loads(res.output)
    # the contact-FE world differs from the model by ~0.2 % in every leg, above the 0.1 % noise: BIC may then keep a
    # factor per leg; either way the located cause is b2's drive
    assert obj["best"]["what"] in ("drive in legs b2", "drive by leg"), obj["best"]
    if not joint_fe:
        assert obj["best"]["what"] == "drive in legs b2"
    loc = obj["located"]
    assert loc["cause"] == "drive_in_legs" and loc["legs"] == ["b2"]
    assert loc["factor"] == pytest.approx(2.0, rel=0.03)
    assert loc["factor_ci"][0] < 2.0 * 1.03 and loc["factor_ci"][1] > 2.0 / 1.03


def _delta_with_crank_pin(tmp_path):
    """The Delta with a pin-in-bore table on its actuated R joint (the crank's pin in the base clevis)."""
    text = DELTA.read_text()
    drive = next(ln for ln in text.splitlines() if ln.strip().startswith("drive = {") and "torsional" in ln)
    pins = ('  hertz_line = { pin_radius_m = 0.0015, contact_length_m = 0.005, pin_span_m = 0.010, '
            'pin_material = "steel", bore_material = "steel" }')
    path = tmp_path / "delta_crank_pin.toml"
    path.write_text(text.replace(drive, drive + "\n" + pins))
    return load_case(path)


def test_a_revolute_with_pins_gets_the_held_hub_specimen(tmp_path):
    from femcheck.parallel.joint_specimen import device_joints
    joints = device_joints(_delta_with_crank_pin(tmp_path))
    assert [(j.joint, j.kind, j.fe_joint, j.specimen.hub_held) for j in joints] == [
        (0, "revolute", "universal", True), (1, "universal", "universal", False), (2, "universal", "universal", False)]


@pytest.mark.slow
def test_revolute_pin_law_is_one_of_the_crosss_two_pins(tmp_path):
    """The crank's pin in its bores (the cross's mesh with the hub held) against the U joint of the same pins: the U
    joint carries the axial load through two such pin-in-bore stages in series, the revolute through one, so it is
    about twice as stiff (1.5-2.5; measured 1.85-1.88 over the ladder); and like the U joint it lies between the
    line contact alone and the simply supported pin in series with it. With it, the Delta's coverage keeps
    hertz_line as contact_fe and >= 90 % covered."""
    from femcheck.coverage.device_coverage import device_coverage
    from femcheck.fe_device.contact_scales import device_springs
    from femcheck.parallel.beam_fe import fe_laws_of
    from femcheck.parallel.joint_specimen import device_joints
    case = _delta_with_crank_pin(tmp_path)
    laws = fe_laws_of(case)
    rev, uj = laws.joints[0, 0], laws.joints[0, 1]
    assert rev[0] == "revolute" and uj[0] == "universal"
    F = rev[1].loads_N
    k_rev = np.array([rev[1].component_stiffness(f)[2] for f in F])
    k_uj = np.array([uj[1].component_stiffness(f)[2] for f in F])
    assert np.all((1.5 < k_rev / k_uj) & (k_rev / k_uj < 2.5)), k_rev / k_uj
    sp = device_springs(device_joints(case)[0].specimen)
    assert np.all(k_rev > 1.0 / (sp.c_uc + sp.c_ub)) and np.all(k_rev < 1.0 / sp.c_uc)
    res = device_coverage(case, fe_laws=laws)
    row = next(e for e in res.elements if e.element == "hertz_line")
    assert row.fe_source == "contact_fe" and res.base_passes and res.covered_share_pct >= 90.0
