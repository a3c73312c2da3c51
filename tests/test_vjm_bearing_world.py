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
from femcheck.vjm.bearing_world import CHA_MODULES, COBOT7_FLANGE_M, COBOT7_SIZES, ISO76_ROLLER_FACTOR, cobot7_bearings_world
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


@pytest.mark.parametrize("size", sorted(CHA_MODULES))
def test_ring_of_45_degree_elements_gives_radial_half_of_axial_and_tilt_from_the_pitch_circle(size):
    """Elements at +-45 deg on the pitch circle: sum cos^2(phi) cos^2(45) = z/4 radially, z/2 axially, and a tilt
    stretches element phi by (dp/2) theta sin(phi): M = axial dp^2 / 8 theta (exact identities, 1e-12)."""
    m = CHA_MODULES[size]
    b = m.bearing(0.0)
    assert b.radial_N_per_m == pytest.approx(b.axial_N_per_m / 2, rel=1e-12)
    assert b.tilt_Nm_per_rad == pytest.approx(b.axial_N_per_m * m.pitch_diameter_m**2 / 8, rel=1e-12)
    assert b.torsion_Nm_per_rad == m.torsion_Nm_per_rad


def test_bearings_sit_at_their_own_places_not_at_the_models_tilt_places(case):
    """The world's bearing centres are the flange places minus the catalogue offset R; none coincides with the
    case's tilt_offset_m (the extended model's spring places): 4-24 mm apart (13 mm on average); the check's
    3 mm bound fails if the world is placed at the model's springs."""
    w = cobot7_bearings_world(case)
    off = np.array([b.offset_m for b in w.bearings])
    expect = np.array(COBOT7_FLANGE_M) - np.array([CHA_MODULES[s].flange_offset_m for s in COBOT7_SIZES])
    np.testing.assert_allclose(off, expect, rtol=0, atol=1e-15)
    assert np.all(np.abs(off - np.array([j.tilt_offset_m for j in case.joints])) >= 0.003)


def test_world_reduces_to_the_conventional_vjm_of_its_drives_when_the_structure_is_rigid(case):
    """Rigid links and bearings leave the drives alone: the world is then the conventional VJM with the
    catalogue K3 (closed form J K^-1 J^T W; 1e-9 relative, Cholesky round-off)."""
    from femcheck.vjm.extended_vjm import virtual_jacobian
    w = cobot7_bearings_world(case).with_rigid_structure()
    q = np.radians(np.array(case.identification.configurations_deg[:3], dtype=float))
    W = np.array(case.identification.wrenches[:1])
    d = tcp_deflections(w, q, W).twist[:, 0]
    J = virtual_jacobian(case.chain, q, extended=False)
    k = np.array([CHA_MODULES[s].torsion_Nm_per_rad for s in COBOT7_SIZES])
    ref = np.einsum("mik,k,mjk,j->mi", J, 1 / k, J, W[0])
    np.testing.assert_allclose(d, ref, rtol=1e-9, atol=1e-15)


def test_extended_model_halves_the_conventional_error_on_the_bearings_world(study):
    """Two-sided target, upper side: extended <= 0.5 x conventional (mean over the 26 Table I tests, and over
    the verification tests 9-13). Measured noise-free: conventional 4.82 %, extended 0.18 %."""
    conv, ext = (study.summary(study.fits[k]) for k in ("conventional", "extended"))
    assert ext["table1_all"]["mean"] <= 0.5 * conv["table1_all"]["mean"]
    assert ext["verification"]["mean"] <= 0.5 * conv["verification"]["mean"]


@pytest.mark.xfail(strict=True, reason=(
    "not met: on the world built from catalogue data the extended model's error is 0.18 % mean / 0.44 % max "
    "(noise-free), below the 0.5 % floor. The catalogue drives (K3) and ideal line-contact bearings leave "
    "link bending as the only non-torsion compliance (rigid links: conventional 0.56 %, extended 0.01 %), and "
    "21 springs lump the bending of round tubes closely (even with every bearing stiffness / 100 the extended "
    "error stays at 0.48 %); a floor of 0.5 % needs compliance (bearing seats, "
    "shell housings) that the cited data do not give, and setting it to reach the floor would be tuning."))
def test_the_bearings_world_is_not_the_extended_model(study):
    """Two-sided target, lower side: extended >= 0.5 % mean over the 26 tests (the world is not the model)."""
    assert study.summary(study.fits["extended"])["table1_all"]["mean"] >= 0.5


def test_torsion_share_is_reported_not_fitted(case, study):
    """The world's torsion share is the rigid-structure deflection projected on the full one; nothing sets it.
    Measured 84.5 % mean (seed 002: 76.5 %). The check recomputes it from the two worlds (1e-12)."""
    w = cobot7_bearings_world(case)
    q = np.radians(np.array(case.identification.configurations_deg[:2], dtype=float))
    W = np.array(case.identification.wrenches)
    full = tcp_deflections(w, q, W).twist[:, :, :3]
    rigid = tcp_deflections(w.with_rigid_structure(), q, W).twist[:, :, :3]
    share = np.einsum("mpi,mpi->mp", rigid, full) / np.einsum("mpi,mpi->mp", full, full)
    np.testing.assert_allclose(study.world_torsion_share[:2], share, rtol=1e-12)
    assert 0.5 < study.world_torsion_share[:13, 0].mean() < 1.0


def test_identify_world_bearings_json(capsys):
    """`femcheck identify cases/cobot7.toml --world bearings --json -`: per model the errors (mean and max) and
    the torsion share, and the world's own share; the role line says what the world is."""
    assert main(["identify", "cases/cobot7.toml", "--world", "bearings", "--json", "-"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["world"] == "bearings" and "catalogue" in res["role"]
    for k in ("conventional", "extended"):
        m = res["models"][k]
        for key in ("error_identification_pct", "error_verification_pct"):
            assert set(m[key]) == {"mean", "max"} and m[key]["max"] >= m[key]["mean"] > 0
        assert 0 < m["torsion_share"]["mean"] <= 100
    assert res["models"]["extended"]["error_verification_pct"]["mean"] <= 0.5 * res["models"]["conventional"]["error_verification_pct"]["mean"]
    assert res["world_torsion_share"]["mean"] == pytest.approx(84.5, abs=0.05)   # as printed, 1 decimal


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
