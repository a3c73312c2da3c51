"""The bearings world of the cobot: catalogue drives and output bearings at their real places, beam links.

Geometry caveat: the arm is the KUKA LBR iiwa 7 R800 (cases/cobot7.toml), not seed 002's SHIR5; the world is
femcheck's beam model with catalogue joint data, not the seed's solid FE model.
"""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

import femcheck
from femcheck.cli import main
from femcheck.vjm.bearing_world import (ARCMIN, CHA_MODULES, COBOT7_FLANGE_M, COBOT7_SIZES, ISO76_ROLLER_FACTOR,
                                        cobot7_bearings_world, with_nominal_drives, with_softer_structure)
from femcheck.vjm.beam_world import tcp_deflections
from femcheck.vjm.world_identification import identify_on_world

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case(ROOT / "cases" / "cobot7.toml")


@pytest.fixture(scope="module")
def study(case):
    return identify_on_world(case, cobot7_bearings_world(case))


@pytest.mark.parametrize("size", sorted(CHA_MODULES))
def test_element_size_reproduces_the_catalogue_static_rating(size):
    """ISO 76, C0 = 44 (1 - D cos a / dp) z l D cos a with l = D, z = pi dp / (1.25 D): the element diameter
    femcheck solves for gives back the catalogue C0 (to round-off of the quadratic: 1e-9)."""
    m = CHA_MODULES[size]
    D, dp, c = 1e3 * m.element_diameter_m, 1e3 * m.pitch_diameter_m, math.cos(math.radians(45))
    z = math.pi * dp / (1.25 * D)
    assert ISO76_ROLLER_FACTOR * (1 - D * c / dp) * z * D * D * c == pytest.approx(m.static_rating_N, rel=1e-9)
    assert 0.02 < D / dp < 0.15                       # a rolling element, not a shaft or a grain


@pytest.mark.parametrize("stiffness", ["catalogue", "line_contact"])
@pytest.mark.parametrize("size", sorted(CHA_MODULES))
def test_ring_of_45_degree_elements_gives_radial_half_of_axial_and_tilt_from_the_pitch_circle(size, stiffness):
    """Elements at +-45 deg on the pitch circle: sum cos^2(phi) cos^2(45) = z/4 radially, z/2 axially, and a tilt
    stretches element phi by (dp/2) theta sin(phi): M = axial dp^2 / 8 theta (exact identities, 1e-12). The
    catalogue ring's tilt is the catalogue's K_B (1e-12: one multiplication and one division)."""
    m = CHA_MODULES[size]
    b = m.bearing(0.0, stiffness=stiffness)
    assert b.radial_N_per_m == pytest.approx(b.axial_N_per_m / 2, rel=1e-12)
    assert b.tilt_Nm_per_rad == pytest.approx(b.axial_N_per_m * m.pitch_diameter_m**2 / 8, rel=1e-12)
    assert b.torsion_Nm_per_rad == m.torsion_Nm_per_rad
    if stiffness == "catalogue":
        assert b.tilt_Nm_per_rad == pytest.approx(m.moment_stiffness_Nm_per_rad, rel=1e-12)
    with pytest.raises(ValueError, match="bearing stiffness 'hertz'; expected one of catalogue, line_contact"):
        m.bearing(0.0, stiffness="hertz")


@pytest.mark.parametrize("size, km_1e4_Nm_per_rad", [(32, 100.0), (25, 39.2)])
def test_catalogue_tilting_stiffness_is_the_sha_manual_s_moment_stiffness(size, km_1e4_Nm_per_rad):
    """K_B of the SHG-2UH table (290 and 114 N m/arcmin) converted to SI equals the moment stiffness Km of the
    same gear's actuator in Harmonic Drive Systems' SHA-SG manual (table 1, 100 and 39.2 x 10^4 N m/rad), an
    independent table in other units: to 0.5 % (the tables' rounding: 3 significant digits). A wrong arcmin
    conversion (degrees, or none) misses by a factor 60 or more."""
    assert CHA_MODULES[size].moment_stiffness_Nm_per_rad == pytest.approx(km_1e4_Nm_per_rad * 1e4, rel=5e-3)
    assert ARCMIN == pytest.approx(math.radians(1.0) / 60.0, rel=1e-15)


@pytest.mark.parametrize("size", sorted(CHA_MODULES))
def test_line_contact_estimate_is_far_stiffer_than_the_catalogue_bearing(size):
    """Rigid rings in steel line contact (no ring or housing compliance) are 17.6 (size 17), 23.2 (25) and 20.4
    (32) times stiffer in tilt than the catalogue's K_B of the mounted bearing: the bound 15-25 fails if either
    value moves by a fifth, or if the estimate came out softer than the catalogue."""
    m = CHA_MODULES[size]
    ratio = m.bearing(0.0, stiffness="line_contact").tilt_Nm_per_rad / m.bearing(0.0).tilt_Nm_per_rad
    assert 15.0 < ratio < 25.0


def test_bearings_sit_at_their_own_places_not_at_the_models_tilt_places(case):
    """The world's bearing centres are the flange places minus the catalogue offset R; none coincides with the
    case's tilt_offset_m (the extended model's spring places): 4-24 mm apart (13 mm on average); the check's
    3 mm bound fails if the world is placed at the model's springs."""
    w = cobot7_bearings_world(case)
    off = np.array([b.offset_m for b in w.bearings])
    expect = np.array(COBOT7_FLANGE_M) - np.array([CHA_MODULES[s].flange_offset_m for s in COBOT7_SIZES])
    np.testing.assert_allclose(off, expect, rtol=0, atol=1e-15)
    assert np.all(np.abs(off - np.array([j.tilt_offset_m for j in case.joints])) >= 0.003)


def _gravity_torques(world, q):
    """(m, n) each joint's torque from the arm's weight, N m: the moment about the joint axis of the nodal
    weights of every body beyond it, summed directly (no stiffness involved)."""
    from femcheck.vjm.beam_world import _layout, _self_weight
    from femcheck.vjm.dh import forward_kinematics
    fk = forward_kinematics(world.chain, q)
    out = np.zeros((len(q), world.chain.n_joints))
    for i in range(len(q)):
        lay = _layout(world, fk, i)
        f = _self_weight(world, lay).reshape(-1, 6)[:, :3]
        for j in range(world.chain.n_joints):
            ids = [k for body in lay.body_nodes[j + 1:] for k in body]
            o, z = fk.joint_frames[i][j, :3, 3], fk.joint_frames[i][j, :3, 2]
            out[i, j] = np.einsum("k,ik->", z, np.cross(lay.nodes[ids] - o, f[ids]))
    return out


@pytest.fixture(scope="module")
def rigid_run(case):
    w = cobot7_bearings_world(case, drives="catalogue").with_rigid_structure()
    q = np.radians(np.array(case.identification.configurations_deg[:4], dtype=float))
    W = np.array(case.identification.wrenches)
    return w, q, W, tcp_deflections(w, q, W)


def test_drive_torques_of_the_solved_equilibrium_are_the_statics_of_the_loads(case, rigid_run):
    """The serial arm is statically determinate: under the self-weight each drive carries the moment of the
    weights beyond it about its axis, and a wrench adds J^T W (virtual work). The secant iteration's torques
    must be these (1e-7 of the largest torque: the solve's round-off, K_z's condition number ~1e7 x 1e-16)."""
    from femcheck.vjm.extended_vjm import virtual_jacobian
    w, q, W, res = rigid_run
    tau = res.drive_torque_Nm
    scale = np.abs(tau).max()
    np.testing.assert_allclose(tau[:, 0], _gravity_torques(w, q), rtol=0, atol=1e-7 * scale)
    J = virtual_jacobian(case.chain, q, extended=False)
    np.testing.assert_allclose(tau[:, 1:] - tau[:, :1], np.einsum("mik,pi->mpk", J, W), rtol=0, atol=1e-7 * scale)
    assert np.all(res.iterations <= 3)                # exact torques after one solve, confirmed by the next
    assert np.abs(tau[:, 0]).max() > 29.0             # the weight takes the shoulder beyond T1: the law matters


def test_rigid_structure_leaves_the_drives_on_the_secant_between_self_weight_and_loaded_torque(case, rigid_run):
    """Rigid links and bearings leave the drives alone: the wrench's TCP twist is J dphi with, per drive, dphi =
    phi(tau_g + J^T W) - phi(tau_g) of its catalogue law (closed form; 1e-7: torques to 1e-7 relative)."""
    from femcheck.vjm.extended_vjm import virtual_jacobian
    w, q, W, res = rigid_run
    J = virtual_jacobian(case.chain, q, extended=False)
    tg = _gravity_torques(w, q)
    tw = np.einsum("mik,pi->mpk", J, W)
    laws = [CHA_MODULES[s].torsion for s in COBOT7_SIZES]
    dphi = np.stack([laws[j].angle(tg[:, None, j] + tw[:, :, j]) - laws[j].angle(tg[:, None, j])
                     for j in range(7)], axis=-1)
    ref = np.einsum("mik,mpk->mpi", J, dphi)
    np.testing.assert_allclose(res.twist, ref, rtol=1e-7, atol=1e-7 * np.abs(ref).max())
    k3 = np.array([CHA_MODULES[s].torsion_Nm_per_rad for s in COBOT7_SIZES])
    linear = np.einsum("mik,mpk->mpi", J, tw / k3)
    assert np.abs(res.twist - linear).max() > 0.1 * np.abs(linear).max()   # K1..K3, not K3 alone


# The tests below measure on the bearings world, whose mitred corners come from the solid FE superelement:
# built cold in about 4 s CPU (three tube sizes, 28 224 DOFs each), then read from the FE cache. The default
# drives are seed 002's reading (constant K3); the catalogue law is the variant ``drives="catalogue"``.

def test_extended_model_halves_the_conventional_error_on_the_bearings_world(study):
    """Two-sided target, upper side: extended <= 0.5 x conventional, mean over the 26 Table I tests (measured
    6.68 % against 15.38 %, 0.434) and over the verification tests 9-13 (12.41 against 25.16 %, 0.493: the
    margin there is small, the check fails with corners 1.3 times as compliant)."""
    conv, ext = (study.summary(study.fits[k]) for k in ("conventional", "extended"))
    assert ext["table1_all"]["mean"] <= 0.5 * conv["table1_all"]["mean"]
    assert ext["verification"]["mean"] <= 0.5 * conv["verification"]["mean"]
    assert ext["table1_all"]["mean"] == pytest.approx(6.68, abs=0.05)      # as measured, 2 decimals
    assert conv["table1_all"]["mean"] == pytest.approx(15.38, abs=0.05)


def test_the_bearings_world_is_not_the_extended_model(study):
    """Two-sided target, lower side: extended >= 0.5 % mean over the 26 tests (the world is not the model).
    Measured noise-free 6.68 %: the mitred corners' compliance is no spring the model has (with rigid corners
    the same world gives 0.26 %: test_nominal_drives_meet_the_floor_only_with_the_mitred_corners)."""
    assert study.summary(study.fits["extended"])["table1_all"]["mean"] >= 0.5


@pytest.mark.xfail(strict=True, reason=(
    "not met with the catalogue's piecewise drive law (drives='catalogue': K1, K2, K3 over 0-T1-T2 at each pose's "
    "self-weight torque): the extended model's error is 8.30 % mean against the conventional 14.16 % over the "
    "26 Table I tests (ratio 0.586). Each drive then works on the secant of its curve between the self-weight "
    "torque and the loaded one (0.54-0.92 K3), different in every pose, which no constant spring of either VJM "
    "holds; that error is common to both models and keeps the ratio above 0.5. Seed 002's FE sets the drives to "
    "their nominal value (the default world, which meets the target); the halving with the law needs bearings "
    "about 1.7 times softer than the catalogue's K_B (test_halving_with_the_catalogue_law_needs_softer_bearings)."))
def test_extended_model_halves_the_conventional_error_with_the_catalogue_drive_law(case):
    r, c, e = _ratio_and_errors(case, cobot7_bearings_world(case, drives="catalogue"))
    assert e <= 0.5 * c


def test_torsion_share_is_reported_not_fitted(case, study):
    """The world's torsion share is the rigid-structure deflection projected on the full one; nothing sets it.
    Measured 55.0 % mean (70.3 % with rigid corners; seed 002: 76.5 %, which nothing here was set to). The check
    recomputes it from the two worlds (1e-12)."""
    w = cobot7_bearings_world(case)
    q = np.radians(np.array(case.identification.configurations_deg[:2], dtype=float))
    W = np.array(case.identification.wrenches)
    full = tcp_deflections(w, q, W).twist[:, :, :3]
    rigid = tcp_deflections(w.with_rigid_structure(), q, W).twist[:, :, :3]
    share = np.einsum("mpi,mpi->mp", rigid, full) / np.einsum("mpi,mpi->mp", full, full)
    np.testing.assert_allclose(study.world_torsion_share[:2], share, rtol=1e-12)
    assert 0.5 < study.world_torsion_share[:13, 0].mean() < 1.0


def _check_json_keys(res, drives="nominal"):
    assert res["world"] == "bearings" and "catalogue" in res["role"] and "mitre" in res["role"]
    assert res["drives"] == drives and res["drives_role"]
    assert res["world_drive_torsion"][0] == (None if drives == "nominal" else
                                             {"limit_torques_Nm": [29.0, 108.0], "stiffness_Nm_per_rad": [67e3, 110e3, 120e3]})
    assert res["world_stiffness_Nm_per_rad"]["torsion"][0] == 120e3        # catalogue K3 of size 32
    for k in ("conventional", "extended"):
        m = res["models"][k]
        for key in ("error_identification_pct", "error_verification_pct"):
            assert set(m[key]) == {"mean", "max"} and m[key]["max"] >= m[key]["mean"] > 0
        assert 0 < m["torsion_share"]["mean"] <= 100
    # the output bearings' tilt is the catalogue's K_B (size 32: 290 N m/arcmin), exactly as stated
    assert res["world_stiffness_Nm_per_rad"]["tilt"][0] == pytest.approx(290.0 / ARCMIN, rel=1e-12)
    assert set(res["target"]) == {"extended_over_conventional", "extended_le_half_conventional", "extended_ge_0_5_pct"}


def test_identify_world_bearings_json(capsys):
    """`femcheck identify cases/cobot7.toml --world bearings --json -`: per model the errors (mean and max) and
    the torsion share, the world's own share, the target; the role lines say what the world and its drives
    are. World torsion share 55.0 % and ratio 0.434 as printed (1 and 3 decimals); both sides met."""
    assert main(["identify", "cases/cobot7.toml", "--world", "bearings", "--json", "-"]) == 0
    res = json.loads(capsys.readouterr().out)
    _check_json_keys(res)
    assert res["world_torsion_share"]["mean"] == pytest.approx(55.0, abs=0.05)
    t = res["target"]
    assert t["extended_over_conventional"] == pytest.approx(0.434, abs=5e-4)
    assert t["extended_le_half_conventional"] is True and t["extended_ge_0_5_pct"] is True


def test_identify_world_bearings_catalogue_drives_json(capsys):
    """`--drives catalogue`: the same keys, the piecewise law in the JSON, ratio 0.586 (halving not met, floor
    met); `--drives` with the beam world or an unknown reading is refused with exit 2 and one line."""
    assert main(["identify", "cases/cobot7.toml", "--world", "bearings", "--drives", "catalogue", "--json", "-"]) == 0
    res = json.loads(capsys.readouterr().out)
    _check_json_keys(res, "catalogue")
    assert res["world_torsion_share"]["mean"] == pytest.approx(63.8, abs=0.05)
    t = res["target"]
    assert t["extended_over_conventional"] == pytest.approx(0.586, abs=5e-4)
    assert t["extended_le_half_conventional"] is False and t["extended_ge_0_5_pct"] is True
    for args in (["--world", "beam", "--drives", "catalogue"], ["--world", "bearings", "--drives", "linear"]):
        assert main(["identify", "cases/cobot7.toml", *args]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--drives" in err[0]


def test_make_data_refuses_an_unknown_drive_reading_and_writes_nothing(tmp_path, capsys):
    """`--make-data --world bearings --drives linear`: exit 2, one line naming --drives, no DATA.csv left."""
    path = tmp_path / "b.csv"
    assert main(["identify", "cases/cobot7.toml", str(path), "--make-data", "--world", "bearings",
                 "--drives", "linear"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--drives" in err[0] and not path.exists()


def test_beam_world_says_it_is_a_check_of_the_assembly(capsys):
    assert main(["identify", "--help"]) == 0
    text = " ".join(re.sub("[\u2500-\u257f]", " ", capsys.readouterr().out).split())   # drop the help's box lines
    assert "check of the assembly" in text and "bearings" in text


def test_bearings_world_data_through_the_csv_path_gives_the_same_fit(tmp_path, capsys, study):
    """--make-data --world bearings writes the world's measurements as DATA.csv; `identify` on it gives the
    compliances of the --world run (the same least squares on the same numbers, 1e-9)."""
    path = tmp_path / "b.csv"
    assert main(["identify", "cases/cobot7.toml", str(path), "--make-data", "--world", "bearings"]) == 0
    assert main(["identify", "cases/cobot7.toml", str(path), "--model", "extended", "--json", "-"]) == 0
    res = json.loads(capsys.readouterr().out.split("\n", 1)[1])
    np.testing.assert_allclose(res["compliances"], study.fits["extended"].compliance, rtol=1e-9)


def _ratio_and_errors(case, world):
    """(extended / conventional, conventional %, extended %): means over the 26 Table I tests."""
    st = identify_on_world(case, world)
    c, e = (st.summary(st.fits[k])["table1_all"]["mean"] for k in ("conventional", "extended"))
    return e / c, c, e


def test_softer_structure_divides_the_bearing_springs_and_the_link_moduli_only(case):
    """with_softer_structure(w, b, l, c): radial, axial and tilt / b, tube E (and G) / l, mitred corners'
    compliance x c; drives, places, masses, tool untouched (exact: one division each)."""
    w = cobot7_bearings_world(case)
    s = with_softer_structure(w, bearings=4.0, links=2.0)
    for b0, b1 in zip(w.bearings, s.bearings):
        assert (b1.radial_N_per_m, b1.axial_N_per_m, b1.tilt_Nm_per_rad) == (
            b0.radial_N_per_m / 4.0, b0.axial_N_per_m / 4.0, b0.tilt_Nm_per_rad / 4.0)
        assert (b1.torsion_Nm_per_rad, b1.torsion_curve, b1.offset_m, b1.mass_kg) == (
            b0.torsion_Nm_per_rad, b0.torsion_curve, b0.offset_m, b0.mass_kg)
    assert [t.E_Pa for t in s.links] == [t.E_Pa / 2.0 for t in w.links] and s.tool == w.tool
    assert s.links[0].G_Pa == pytest.approx(w.links[0].G_Pa / 2.0, rel=1e-15)
    assert w.corners == "solid" and w.corner_scale == 1.0 and s.corner_scale == 1.0   # E / 2 softens the corners too
    assert with_softer_structure(w, corners=0.5).corner_scale == 0.5
    with pytest.raises(ValueError, match="with_softer_structure"):
        with_softer_structure(w, bearings=0.0)
    with pytest.raises(ValueError, match="corners=-1"):
        with_softer_structure(w, corners=-1.0)


def test_nominal_drives_meet_the_floor_only_with_the_mitred_corners(case):
    """The seed's FE reading (drives and bearings at "nominal value", sec. IV-A: a linear model): constant K3
    drives. With rigid corners the joints' compliance is what the extended model is built of, and it fits the
    world to 0.26 % (conventional 10.78 %): the floor fails. The solid mitred corners' compliance is no joint
    spring: 15.38 % against 6.68 % (ratio 0.434, both sides met). Each as measured +- 0.05 % (2 decimals)."""
    w = cobot7_bearings_world(case)
    assert all(b.torsion_curve is None for b in w.bearings)             # the default is the nominal reading
    assert w == with_nominal_drives(cobot7_bearings_world(case, drives="catalogue"))   # the law alone differs
    r, c, e = _ratio_and_errors(case, w)
    assert c == pytest.approx(15.38, abs=0.05) and e == pytest.approx(6.68, abs=0.05)
    r, c, e = _ratio_and_errors(case, cobot7_bearings_world(case, corners="rigid"))
    assert e < 0.5 and c == pytest.approx(10.78, abs=0.05)


def test_catalogue_bearings_move_the_ratio_from_the_line_contact_estimate_s(case):
    """The bearing value matters: the line-contact estimate (rigid rings, 18-23 times stiffer) gives 12.78 %
    against 9.42 % (ratio 0.737), the catalogue's K_B 14.16 % against 8.30 % (0.586). Each ratio as measured,
    +-0.005 (3 decimals); they fail if the two worlds are the same bearings."""
    r_line = _ratio_and_errors(case, cobot7_bearings_world(case, "line_contact", drives="catalogue"))[0]
    r_cat = _ratio_and_errors(case, cobot7_bearings_world(case, drives="catalogue"))[0]
    assert r_line == pytest.approx(0.737, abs=5e-3) and r_cat == pytest.approx(0.586, abs=5e-3)


def test_halving_with_the_catalogue_law_needs_softer_bearings(case):
    """With the catalogue drive law, how far the halving's failure depends on the catalogue's K_B (an average
    value): the ratio crosses 0.5 only with bearings between 1.5 and 2 times softer (0.523, 0.471). The bracket
    fails if the crossing moves out of it (either side)."""
    w = cobot7_bearings_world(case, drives="catalogue")
    lo, hi = (_ratio_and_errors(case, with_softer_structure(w, bearings=f))[0] for f in (1.5, 2.0))
    assert lo > 0.5 > hi


def test_with_the_catalogue_law_the_corners_do_not_reach_the_halving(case):
    """With the catalogue drive law the corners' compliance is no lever for the verdict: at half and at twice
    the solid's the ratio is 0.581 and 0.626, both above 0.5 (as measured +- 0.005)."""
    w = cobot7_bearings_world(case, drives="catalogue")
    half, double = (_ratio_and_errors(case, with_softer_structure(w, corners=f))[0] for f in (0.5, 2.0))
    assert half == pytest.approx(0.581, abs=5e-3) and double == pytest.approx(0.626, abs=5e-3)


def test_the_default_verdict_holds_within_a_factor_of_two_of_the_corners_but_not_beyond(case):
    """The margin of the default world's verdict (nominal drives), stated rather than hidden: the corners'
    compliance x 0.5 gives 0.294, x 2 gives 0.559 (the halving then fails); bearings 2 x softer 0.328, 2 x
    stiffer 0.514. As measured +- 0.005 (3 decimals); the check fails if the world's sensitivity changes."""
    w = cobot7_bearings_world(case)
    got = [_ratio_and_errors(case, with_softer_structure(w, **kw))[0]
           for kw in ({"corners": 0.5}, {"corners": 2.0}, {"bearings": 2.0}, {"bearings": 0.5})]
    np.testing.assert_allclose(got, [0.294, 0.559, 0.328, 0.514], rtol=0, atol=5e-3)
