"""The 6-PSU reference case (cases/haptic_6psu.toml, a parallel_device written leg by leg) on the general model
against its five-element view ``femcheck.chain`` (the same model on the legs with the parameters derived from the
layout tables, :func:`femcheck.chain.device_parameters`): the same numbers, element by element, and the IK."""
from __future__ import annotations

import numpy as np
import pytest

from femcheck.case import load_case
from femcheck.chain import evaluate as evaluate_6psu
from femcheck.kinematics.psu6 import leg_geometry, test_points as cube_points
from femcheck.parallel.beam_fe import device_fe_stiffness
from femcheck.parallel.chain_model import evaluate
from femcheck.parallel.leg_kinematics import solve_legs
from tests.conftest import ROOT

#: the 6-PSU baselines' bar; the two differ only by the rounding of the parameters' two derivations
RTOL = 1e-9
#: the five-element order of femcheck.chain and the names of the same elements in the parallel_device file
NAMES = ("guideway", "drive", "hertz_point", "proximal_link", "hertz_line")


@pytest.fixture(scope="module")
def cases():
    case = load_case(ROOT / "cases" / "haptic_6psu.toml")
    return case, case


def _poses(c6):
    rng = np.random.default_rng(11)
    P = np.tile(cube_points(c6)[0], (20, 1))
    P[:, :3] += rng.uniform(-0.03, 0.03, (20, 3))
    P[:, 3:] = rng.uniform(-0.05, 0.05, (20, 3))
    return np.vstack([cube_points(c6), P])


@pytest.mark.parametrize("model", ["simplified", "detailed"])
@pytest.mark.parametrize("joints", ["rigid", "released"])
@pytest.mark.parametrize("wrench", [None, [0, 0, 15, 0, 0, 0], [15, -5, 0, 0.1, 0, 0]])
@pytest.mark.parametrize("backend", ["compiled", "numpy"])
def test_general_model_reproduces_the_6psu_chain(cases, model, joints, wrench, backend):
    c6, cp = cases
    P = _poses(c6)
    a = evaluate_6psu(c6, P, wrench, model=model, joints=joints)
    b = evaluate(cp.device, P, wrench, model=model, joints=joints, backend=backend)
    assert np.abs(a.K - b.K).max() < RTOL * np.abs(a.K).max()
    if wrench is not None:
        cols = [b.element_names.index(n) for n in NAMES]
        assert np.allclose(a.contributions, b.contributions[:, cols], rtol=0, atol=RTOL)


def test_numeric_ik_gives_the_6psu_slider_positions(cases):
    c6, cp = cases
    P = _poses(c6)
    s6 = leg_geometry(c6, P).slider
    state = solve_legs(cp.device, P, backend="numpy")
    home = np.array([np.linalg.norm(leg.centres[1] - leg.centres[0]) for leg in cp.device.legs])
    s = home + np.stack([st.q[:, leg.actuated_dof] for leg, st in zip(cp.device.legs, state.legs)], axis=1)
    assert np.abs(s - s6).max() < 1e-10  # the IK stops at 1e-11 m


def test_closed_form_slider_positions(cases):
    """The compiled path's closed form (slider from the sphere |C - B| = L) against the 6-PSU's IK."""
    c6, cp = cases
    P = _poses(c6)
    s6 = leg_geometry(c6, P).slider
    state = solve_legs(cp.device, P)
    assert state.packed[5].all()                             # every leg took the closed form
    home = np.array([np.linalg.norm(leg.centres[1] - leg.centres[0]) for leg in cp.device.legs])
    s = home + np.stack([st.q[:, leg.actuated_dof] for leg, st in zip(cp.device.legs, state.legs)], axis=1)
    assert np.abs(s - s6).max() < 1e-12  # two closed forms of the same root: rounding only (measured 1e-16)


@pytest.mark.parametrize("joints", ["rigid", "released"])
def test_beam_fe_of_the_6psu_legs(cases, joints):
    _, cp = cases
    P = cube_points(cases[0])
    r = evaluate(cp.device, P, [0, 0, 15, 0, 0, 0], joints=joints)
    K = device_fe_stiffness(cp.device, P, joints=joints, hertz_stiffness=r.hertz_stiffness, state=r.state)
    assert np.abs(K - r.K).max() < 1e-8 * np.abs(r.K).max()


@pytest.mark.parametrize("backend", ["compiled", "numpy"])
def test_joint_rotation_springs_equal_the_twist_formulation(cases, backend):
    """Rigid joints with a joint-rotation compliance c: each leg's compliance gains c Jp Jp^T with Jp the unit twists
    at C of the S joint's three rotations about B (any orthonormal axes) and of the U joint's two rotations normal to
    the link at C (seed 001's passive joints with springs); the platform sums the legs at the TCP."""
    from femcheck.parallel.chain_model import leg_element_compliances
    _, cp = cases
    P = cube_points(cases[0])
    c = 2e-3   # rad/(N m): the joint springs carry a visible share of the deflection
    r = evaluate(cp.device, P, [0, 0, 15, 0, 0, 0], model="simplified", joints="rigid", backend=backend,
                 joint_rotation_compliance=c)
    state = solve_legs(cp.device, P)
    parts = leg_element_compliances(cp.device, state, "simplified")
    K = np.zeros((len(P), 6, 6))
    for i, s in enumerate(state.legs):
        B, C = s.centres[:, 1], s.C
        u = (C - B) / np.linalg.norm(C - B, axis=1)[:, None]
        a1 = np.cross([0.0, 0.0, 1.0], u)
        a1 /= np.linalg.norm(a1, axis=1)[:, None]
        J = [np.concatenate([np.cross(np.broadcast_to(w, C.shape), C - B), np.broadcast_to(w, C.shape)], axis=1)
             for w in np.eye(3)]
        J += [np.concatenate([np.zeros_like(a), a], axis=1) for a in (a1, np.cross(u, a1))]
        Jp = np.stack(J, axis=-1)
        S = sum(parts[i].values()) + c * Jp @ np.swapaxes(Jp, 1, 2)
        G = state.G(i)
        K += np.swapaxes(G, 1, 2) @ np.linalg.inv(S) @ G
    # two formulations of the same springs: round-off of the 6x6 inverses
    assert np.abs(K - r.K).max() < 1e-9 * np.abs(r.K).max()
    rigid = evaluate(cp.device, P, [0, 0, 15, 0, 0, 0], model="simplified", joints="rigid", backend=backend)
    assert np.abs(rigid.K - r.K).max() > 1e-3 * np.abs(r.K).max()   # and the springs matter at this c
