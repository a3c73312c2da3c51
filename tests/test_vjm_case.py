"""serial_robot and parallel_vjm case files: validation errors name the file and the dotted key."""
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from femcheck.case import build_case, load_case
from femcheck.errors import CaseError

CASES = Path("cases")


def _raw(name):
    return tomllib.loads((CASES / name).read_text())


def _expect(raw, key_pattern, path="x.toml"):
    with pytest.raises(CaseError) as info:
        build_case(raw, path)
    msg = str(info.value)
    assert msg.startswith(f"{path}: "), msg
    assert re.search(key_pattern, msg), msg
    return msg


def test_shipped_cases_load():
    irb, cobot, hiss = (load_case(CASES / n) for n in ("irb120.toml", "cobot7.toml", "hiss.toml"))
    assert irb.kind == "serial_robot" and irb.n_joints == 6 and irb.chain.convention == "modified"
    assert cobot.model.vjm == "extended" and cobot.virtual_stiffness.shape == (21,) and cobot.chain.convention == "standard"
    assert hiss.kind == "parallel_vjm" and hiss.K_theta.shape == (18, 18) and len(hiss.test_points) == 13


def test_serial_errors_name_file_and_key():
    raw = _raw("irb120.toml")
    raw["kinematics"]["convention"] = "craig"
    _expect(raw, r"kinematics\.convention: got 'craig'; expected one of \['standard', 'modified'\]")

    raw = _raw("irb120.toml")
    raw["joints"][2]["stiffness_Nm_per_rad"] = 1.0e4          # both direct and drive train
    _expect(raw, r"joints\[2\]\.stiffness_Nm_per_rad: give either")

    raw = _raw("irb120.toml")
    del raw["joints"][2]["drive_train"][1]["width_m"]          # timing belt incomplete
    _expect(raw, r"joints\[2\]\.drive_train\[1\]\.width_m: a timing_belt needs exactly")

    raw = _raw("irb120.toml")
    raw["joints"][0]["drive_train"][1]["ratio"] = -120         # negative ratio
    _expect(raw, r"joints\[0\]\.drive_train\[1\]\.ratio: = -120")

    raw = _raw("irb120.toml")
    raw["joints"][4]["a_mm"] = 3.0                            # unknown key
    _expect(raw, r"joints\[4\]\.a_mm: unknown key")

    raw = _raw("cobot7.toml")
    del raw["joints"][6]["tilt_stiffness_Nm_per_rad"]
    _expect(raw, r"joints\[6\]\.tilt_stiffness_Nm_per_rad: required when model.vjm = 'extended'")

    raw = _raw("cobot7.toml")
    raw["identification"]["configurations_deg"][3] = [0, 0, 0]
    _expect(raw, r"identification\.configurations_deg\[3\]: has 3 angles; expected 7")


def test_parallel_errors_name_file_and_key():
    raw = _raw("hiss.toml")
    raw["links"]["coupler"]["stiffness"][0][1] = 1.0            # breaks symmetry
    _expect(raw, r"links\.coupler\.stiffness: not symmetric")

    raw = _raw("hiss.toml")
    raw["test_points"][4]["active_deg"] = [0, 0, 45]
    _expect(raw, r"test_points\[4\]\.active_deg: 45")

    raw = _raw("hiss.toml")
    raw["fitting"]["weight_map"] = raw["fitting"]["weight_map"][:17]
    _expect(raw, r"fitting\.weight_map: has 17 entries; expected 18")

    raw = _raw("hiss.toml")
    raw["geometry"]["crank_length_m"] = 0.0
    _expect(raw, r"geometry\.crank_length_m: = 0.0 m; expected > 0")


def test_variants_are_new_objects():
    irb = load_case(CASES / "irb120.toml")
    stiffer = irb.with_params(**{"model.complementary_stiffness": False})
    assert irb.model.complementary_stiffness and not stiffer.model.complementary_stiffness
    np.testing.assert_array_equal(irb.joint_stiffness, stiffer.joint_stiffness)
