"""Test-point labels become poses in one module (:mod:`femcheck.kinematics.points`), for every case kind."""
from __future__ import annotations

import re

import numpy as np
import pytest

from femcheck.case import load_case
from tests.conftest import ROOT

#: a label looked up by position in the label tuple: what only kinematics.points may do
LOOKUP = re.compile(r"POINT_LABELS\.index\(")


def test_labels_are_resolved_in_one_module():
    found = [str(f.relative_to(ROOT)) for f in (ROOT / "femcheck").rglob("*.py")
             if LOOKUP.search(f.read_text(encoding="utf-8"))]
    assert found == ["femcheck/kinematics/points.py"], found


@pytest.mark.parametrize("name", ["haptic_6psu", "hexapod_6ups", "delta_3ruu"])
def test_test_poses_are_the_cube_of_the_case(name):
    """P0 is the nominal TCP and P1..P8 the cube corners at +-edge/2 (exact: the same sums)."""
    from femcheck.kinematics.points import test_poses
    case = load_case(ROOT / "cases" / f"{name}.toml")
    P = test_poses(case, ("P0", "P7"))
    assert P.shape == (2, 6)
    half = 0.5 * case.workspace.cube_edge_m
    assert np.abs(P[1, :3] - P[0, :3]) == pytest.approx([half] * 3, rel=1e-12)
    with pytest.raises(ValueError, match="P9"):
        test_poses(case, ("P9",))
