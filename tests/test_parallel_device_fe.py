"""Beam FE of the parallel devices from the case description vs the general chain model (issue 19 item 3)."""
from __future__ import annotations

import numpy as np
import pytest

from femcheck.case import load_case
from femcheck.parallel.beam_fe import device_fe_stiffness
from femcheck.parallel.chain_model import evaluate
from femcheck.parallel.device import test_points as cube_points
from tests.conftest import ROOT

CASES = [ROOT / "cases" / "hexapod_6ups.toml", ROOT / "cases" / "delta_3ruu.toml"]
#: beam elements are exact at the nodes for end loads and the joints are exact constraints, so only rounding
#: separates the two (measured ~1e-12); the issue asks for 1e-8
FE_RTOL = 1e-8


@pytest.mark.parametrize("path", CASES, ids=["hexapod", "delta"])
@pytest.mark.parametrize("model", ["simplified", "detailed"])
@pytest.mark.parametrize("joints", ["rigid", "released"])
def test_beam_fe_reproduces_the_chain_model(path, model, joints):
    case = load_case(path)
    dev = case.device
    P = cube_points(case)
    r = evaluate(dev, P, [3.0, -4.0, case.loads.test_N, 0, 0, 0], model=model, joints=joints)
    K_fe = device_fe_stiffness(dev, P, model=model, joints=joints, hertz_stiffness=r.hertz_stiffness, state=r.state)
    assert np.abs(K_fe - r.K).max() < FE_RTOL * np.abs(r.K).max()
    # the compliance too (the soft directions are what a user reads)
    S_fe = np.linalg.inv(K_fe)
    assert np.abs(S_fe - r.S).max() < FE_RTOL * np.abs(r.S).max()


@pytest.mark.parametrize("path", CASES, ids=["hexapod", "delta"])
def test_beam_fe_with_shear_and_finer_mesh(path):
    case = load_case(path).with_params(**{"model.beam_shear": True})
    dev = case.device
    P = cube_points(case)[[0, 6]]
    r = evaluate(dev, P, None, model="detailed", joints="rigid")
    K_fe = device_fe_stiffness(dev, P, model="detailed", joints="rigid", hertz_stiffness=r.hertz_stiffness,
                               elements_per_link=5)
    assert np.abs(K_fe - r.K).max() < FE_RTOL * np.abs(r.K).max()


def test_detailed_needs_the_hertz_linearization():
    case = load_case(CASES[0])
    with pytest.raises(ValueError, match="hertz_stiffness"):
        device_fe_stiffness(case.device, cube_points(case)[:1], model="detailed")
