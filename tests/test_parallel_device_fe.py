"""Beam FE of the parallel devices from the case description vs the general chain model."""
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


@pytest.mark.parametrize("element", ["tube", "bar"])
def test_solid_link_against_the_cantilever_closed_forms(element):
    """A solid link (geometry builder, P2, condensed; coarse) clamped at its start: tip axial compliance L/EA
    within 2 % (the rigid end faces block the Poisson contraction: the bar, L/h = 8, measures 1.2 % stiffer),
    tube torsion L/GJ and bending L^3/(3EI) + L/(kGA) (Timoshenko) within 3 % (end faces, faceted section); the
    bar's torsion is stiffer than free Saint-Venant torsion (rigid end faces restrain warping; measured 7 %),
    and the 12 x 12 is symmetric with 6 rigid-body modes."""
    from types import SimpleNamespace
    from femcheck.case.schema import build_materials  # noqa: F401  (materials come from the reference case)
    from femcheck.parallel.solid_links import link_stiffness
    import femcheck
    mat = femcheck.load_case("cases/hexapod_6ups.toml").device.legs[0].links[0].spec.material
    L = 0.12
    if element == "tube":
        spec = SimpleNamespace(element="tube", name="t", material=mat, outer_diameter_m=0.010, inner_diameter_m=0.008,
                               width_m=None, depth_m=None)
        A = np.pi * (0.010**2 - 0.008**2) / 4
        I = np.pi * (0.010**4 - 0.008**4) / 64
        J, kappa = 2 * I, 0.53
    else:
        spec = SimpleNamespace(element="bar", name="b", material=mat, outer_diameter_m=None, inner_diameter_m=0.0,
                               width_m=0.008, depth_m=0.015)
        b, h = 0.008, 0.015
        A, I = b * h, h * b**3 / 12          # bending about y: the section's x dimension (width) bends
        a_, c_ = max(b, h), min(b, h)
        J, kappa = a_ * c_**3 * (1 / 3 - 0.21 * c_ / a_ * (1 - c_**4 / (12 * a_**4))), 5 / 6
    K = link_stiffness(spec, L, "coarse")
    assert np.abs(K - K.T).max() < 1e-9 * np.abs(K).max()
    w = np.linalg.eigvalsh(K)
    assert np.sum(np.abs(w) < 1e-8 * w.max()) == 6            # free-free: six rigid-body modes
    C = np.linalg.inv(K[6:, 6:])                               # start node clamped
    E, G = mat.E_Pa, mat.G_Pa
    assert C[2, 2] == pytest.approx(L / (E * A), rel=0.02)
    if element == "tube":
        assert C[5, 5] == pytest.approx(L / (G * J), rel=0.03)
    else:   # rigid end faces restrain the rectangle's warping: stiffer than free Saint-Venant torsion, by < 10 %
        assert 0.90 < C[5, 5] / (L / (G * J)) < 1.0
    print(element, C[2, 2] * E * A / L, C[5, 5] * G * J / L, C[0, 0] / (L**3 / (3 * E * I) + L / (kappa * G * A)))
    assert C[0, 0] == pytest.approx(L**3 / (3 * E * I) + L / (kappa * G * A), rel=0.03)
