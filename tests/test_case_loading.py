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


def _value(case, key):
    """The value of the reference file's dotted ``key`` in the loaded case (its tables, read from the legs)."""
    head, *rest = key.split(".")
    if head == "materials":
        return getattr(case.material(rest[0]), rest[1])
    if head == "meta" and rest == ["kind"]:
        return "haptic_6psu" if case.kind == "haptic_6psu" else case.meta.kind
    node = getattr(case, head)
    for r in rest:
        node = getattr(node, r)
    return node.name if isinstance(node, femcheck.case.schema.Material) else node


@pytest.mark.skipif(not SHARED_REFERENCE.is_file(), reason="shared/reference not beside the checkout")
def test_case_file_carries_every_reference_value():
    """The reference numbers (the tables of the paper's layout) are what the leg-by-leg case holds."""
    ours = femcheck.load_case(REFERENCE_CASE)
    ref = dict(_flatten(tomllib.loads(SHARED_REFERENCE.read_text())))
    for key, value in ref.items():
        if key == "meta.conventions":   # a pointer to the conventions document, which the repository carries itself
            continue
        v = _value(ours, key)
        v = [list(r) for r in v] if key == "workspace.corner_signs" else list(v) if isinstance(v, tuple) else v
        assert v == value, key


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
    # the 6-PSU is written leg by leg: the first occurrence of a part's key is in leg 0
    (("outer_diameter_m = 0.006", "outer_diameter_m = -0.006"), "legs[0].links[1].outer_diameter_m", "expected > 0"),
    (("pin_radius_m = 0.001", 'pin_radius_m = "thin"'), "legs[0].joints[3].hertz_line.pin_radius_m", "expected a number"),
    (('joint_rotations = "rigid"', 'joint_rotations = "floppy"'), "model.joint_rotations", "expected one of"),
    (('material = "aluminium"', 'material = "unobtainium"'), "legs[0].links[0].material", "not defined"),
    (("nu = 0.30", "nu = 0.7"), "materials.steel.nu", "Poisson"),
    (("cable_length_m = 0.9", "cable_lenght_m = 0.9"), "legs[0].joints[1].drive.cable_lenght_m", "unknown key"),
    (("inner_diameter_m = 0.005", "inner_diameter_m = 0.007"), "legs[0].links[1].inner_diameter_m", "outer_diameter_m"),
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
    text = REFERENCE_CASE.read_text().replace("shaft_length_m = 0.025, ", "")
    with pytest.raises(CaseError, match=r"legs\[0\].joints\[1\].drive.shaft_length_m: required for an? axial drive"):
        femcheck.load_case(_write(tmp_path, text))
    with pytest.raises(CaseError, match="case file not found"):
        femcheck.load_case(tmp_path / "nope.toml")
    with pytest.raises(CaseError, match="not valid TOML"):
        femcheck.load_case(_write(tmp_path, "[meta\nname="))
