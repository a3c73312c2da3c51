"""One implementation of each element law: a law replaced in its module moves the compiled (numba) chain kernels
exactly as it moves the numpy chain models, in the same process, and putting it back restores them bit for bit."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import femcheck
from femcheck.chain import evaluate
from femcheck.compliance import cantilever_beam, hertz_point_contact

ROOT = Path(__file__).resolve().parents[1]
W = np.array([20.0, 0.0, 0.0, 0.0, 0.0, 0.0])


def _hertz_3x_compliant(f):
    def broken(F, E_star, R_star):     # k ~ E*^(2/3): the contact compliance x 3
        return f(F, E_star * 3.0 ** -1.5, R_star)
    return broken


def _cantilever_2x_softer(f):
    def broken(L, E, G, A, Ix, Iy, Jt, shear_factor, shear):
        return f(L, 0.5 * E, 0.5 * G, A, Ix, Iy, Jt, shear_factor, shear)
    return broken


LAWS = {"hertz": (hertz_point_contact, "hertz_tangent_stiffness", _hertz_3x_compliant),
        "cantilever": (cantilever_beam, "cantilever_terms", _cantilever_2x_softer)}


@pytest.fixture(scope="module")
def psu():
    case = femcheck.load_case(ROOT / "cases" / "haptic_6psu.toml")
    return case, femcheck.test_points(case)


@pytest.mark.parametrize("joints", ["rigid", "released"])
@pytest.mark.parametrize("law", list(LAWS))
def test_law_replaced_in_its_module_moves_the_6psu_chain(law, joints, psu, monkeypatch):
    case, P = psu
    module, attr, make = LAWS[law]
    before = evaluate(case, P, W, joints=joints).twist
    monkeypatch.setattr(module, attr, make(getattr(module, attr)))
    compiled = evaluate(case, P, W, joints=joints).twist
    reference = evaluate(case, P, W, joints=joints, backend="numpy").twist
    # the broken law is felt: the spherical joints carry ~10 % of the x deflection and the beams more, so
    # tripling / doubling their compliance moves every pose by well over 1 %
    assert np.all(np.abs(compiled[:, 0] / before[:, 0] - 1.0) > 0.01)
    # and the kernel uses the same law as the numpy model (the backends agree to 1e-10 unbroken, too)
    assert np.abs(compiled - reference).max() < 1e-10 * np.abs(reference).max()
    monkeypatch.undo()
    np.testing.assert_array_equal(evaluate(case, P, W, joints=joints).twist, before)   # the module's law again


@pytest.mark.parametrize("law", list(LAWS))
def test_law_replaced_in_its_module_moves_the_parallel_kernel(law, monkeypatch):
    """The general parallel-device kernel on the 6-PSU described leg by leg (cantilever links, Hertz ball joints):
    the device is rebuilt for the new law (its cache is keyed on the law functions) and both kernels
    (chain_kernel on a solved state, evaluate_kernel fused with the inverse kinematics) follow the law."""
    from femcheck.parallel.chain_model import evaluate as evaluate_parallel
    from femcheck.parallel.device import test_points as cube_points
    from femcheck.parallel.leg_kinematics import solve_legs

    case = femcheck.load_case(ROOT / "cases" / "haptic_6psu.toml")
    P = cube_points(case)
    before = evaluate_parallel(case.device, P, W, model="detailed", joints="rigid").twist
    module, attr, make = LAWS[law]
    monkeypatch.setattr(module, attr, make(getattr(module, attr)))
    dev = case.device
    fused = evaluate_parallel(dev, P, W, model="detailed", joints="rigid").twist
    on_state = evaluate_parallel(dev, P, W, model="detailed", joints="rigid", state=solve_legs(dev, P)).twist
    reference = evaluate_parallel(dev, P, W, model="detailed", joints="rigid", backend="numpy").twist
    assert np.all(np.abs(fused[:, 0] / before[:, 0] - 1.0) > 0.01)    # as for the 6-PSU chain
    for got in (fused, on_state):
        assert np.abs(got - reference).max() < 1e-9 * np.abs(reference).max()   # the backends' bar (RTOL)
