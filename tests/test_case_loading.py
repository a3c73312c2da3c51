"""Case files load into immutable, validated model objects; errors name the file and the key."""
from __future__ import annotations

import dataclasses
import tomllib

import pytest

import femcheck
from femcheck.errors import CaseError
from tests.conftest import REFERENCE_CASE, SHARED_REFERENCE


def _flatten(d, prefix=""):
    for k, v in d.items():
        if isinstance(v, dict):
            yield from _flatten(v, f"{prefix}{k}.")
        else:
            yield f"{prefix}{k}", v


@pytest.mark.skipif(not SHARED_REFERENCE.is_file(), reason="shared/reference not beside the checkout")
def test_case_file_carries_every_reference_value():
    ours = dict(_flatten(tomllib.loads(REFERENCE_CASE.read_text())))
    ref = dict(_flatten(tomllib.loads(SHARED_REFERENCE.read_text())))
    for key, value in ref.items():
        if key == "meta.conventions":   # a pointer to the conventions document, which the repository carries itself
            continue
        assert ours[key] == value, key


def test_loaded_values_and_derived_geometry(case):
    assert case.guideway.material.E_Pa == 69.0e9
    assert case.spherical_joint.seat_material.name == "uhmwpe"
    assert case.base_points.shape == (6, 3)
    # base pairs symmetric about the x axis for pair 0 (docs/conventions.md §2), radius R_b
    assert case.base_points[0, 1] == pytest.approx(-case.base_points[1, 1])
    assert (case.base_points[:, :2] ** 2).sum(1) == pytest.approx([case.geometry.base_radius_m**2] * 6)


def test_case_is_immutable(case):
    with pytest.raises(dataclasses.FrozenInstanceError):
        case.guideway = None  # type: ignore[misc]


def test_with_params_makes_a_validated_variant(case):
    v = case.with_params(**{"guideway.width_radial_m": 0.02})
    assert v.guideway.width_radial_m == 0.02 and case.guideway.width_radial_m == 0.014
    assert v.sha256 != case.sha256


def _write(tmp_path, text):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize("edit, key, words", [
    (("outer_diameter_m = 0.006", "outer_diameter_m = -0.006"), "proximal_link.outer_diameter_m", "expected > 0"),
    (("pin_radius_m = 0.0010", 'pin_radius_m = "thin"'), "universal_joint.pin_radius_m", "expected a number"),
    (('joint_rotations = "rigid"', 'joint_rotations = "floppy"'), "model.joint_rotations", "expected one of"),
    (('material = "aluminium"', 'material = "unobtainium"'), "guideway.material", "not defined"),
    (("nu = 0.30", "nu = 0.7"), "materials.steel.nu", "Poisson"),
    (("cable_length_m = 0.90", "cable_lenght_m = 0.90"), "actuation.cable_lenght_m", "unknown key"),
    (("inner_diameter_m = 0.005", "inner_diameter_m = 0.007"), "proximal_link.inner_diameter_m", "outer_diameter_m"),
])
def test_invalid_case_names_file_and_key(tmp_path, edit, key, words):
    text = REFERENCE_CASE.read_text()
    assert edit[0] in text
    path = _write(tmp_path, text.replace(edit[0], edit[1], 1))
    with pytest.raises(CaseError) as err:
        femcheck.load_case(path)
    msg = str(err.value)
    assert str(path) in msg and key in msg and words in msg, msg


def test_missing_key_and_missing_file(tmp_path):
    text = REFERENCE_CASE.read_text().replace("shaft_length_m = 0.025", "")
    with pytest.raises(CaseError, match="actuation.shaft_length_m: required key is missing"):
        femcheck.load_case(_write(tmp_path, text))
    with pytest.raises(CaseError, match="case file not found"):
        femcheck.load_case(tmp_path / "nope.toml")
    with pytest.raises(CaseError, match="not valid TOML"):
        femcheck.load_case(_write(tmp_path, "[meta\nname="))
