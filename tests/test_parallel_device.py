"""The general parallel-device model against closed forms and independent derivations."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from femcheck.case import load_case
from femcheck.errors import CaseError
from femcheck.kinematics.frames import rot6, rotvec_to_matrix, matrix_to_rotvec
from femcheck.parallel.chain_model import evaluate
from femcheck.parallel.device import test_points as cube_points
from femcheck.parallel.leg_kinematics import actuation_jacobian, solve_legs

ROOT = Path(__file__).resolve().parents[1]
HEXAPOD = ROOT / "cases" / "hexapod_6ups.toml"
DELTA = ROOT / "cases" / "delta_3ruu.toml"

#: the inverse kinematics stops at a residual of 1e-11 (m and rad); 1e-10 leaves a margin for the summation
IK_TOL = 1e-10
#: closed forms evaluated with the same double-precision inputs: only rounding separates them
CLOSED_FORM_RTOL = 1e-9


@pytest.fixture(scope="module")
def hexapod():
    return load_case(HEXAPOD)


@pytest.fixture(scope="module")
def delta():
    return load_case(DELTA)


def _random_poses(case, n, seed, dx=0.02, drot=0.1, rotate=True):
    rng = np.random.default_rng(seed)
    P = np.tile(cube_points(case)[0], (n, 1))
    P[:, :3] += rng.uniform(-dx, dx, (n, 3))
    if rotate:
        P[:, 3:] = rng.uniform(-drot, drot, (n, 3))
    return P


def test_reference_devices_load(hexapod, delta):
    assert hexapod.device.n_legs == 6 and delta.device.n_legs == 3
    assert [leg.name for leg in hexapod.device.legs] == ["a1", "b1", "a2", "b2", "a3", "b3"]
    assert solve_legs(hexapod.device, cube_points(hexapod)).ok.all()
    assert solve_legs(delta.device, cube_points(delta)).ok.all()


def test_hexapod_numeric_ik_matches_closed_form(hexapod):
    dev = hexapod.device
    P = _random_poses(hexapod, 200, 1)
    state = solve_legs(dev, P)
    assert state.ok.all()
    R = rotvec_to_matrix(P[:, 3:])
    for leg, s in zip(dev.legs, state.legs):
        a = leg.centres[0]
        closed = np.linalg.norm(P[:, :3] + R @ leg.b_platform - a, axis=1)  # leg length |p + R b - a|
        home = np.linalg.norm(leg.centres[-1] - a)
        numeric = home + s.q[:, leg.actuated_dof]
        assert np.abs(numeric - closed).max() < IK_TOL


def test_hexapod_jacobian_rows_are_the_strut_lines(hexapod):
    dev = hexapod.device
    P = _random_poses(hexapod, 50, 2)
    state = solve_legs(dev, P)
    J = actuation_jacobian(dev, state)
    for i, s in enumerate(state.legs):
        u = s.C - dev.legs[i].centres[0]
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        row = np.concatenate([u, np.cross(s.C - state.tcp, u)], axis=1)
        assert np.abs(J[:, i] - row).max() < 1e-9


@pytest.mark.parametrize("path", [HEXAPOD, DELTA])
def test_jacobian_matches_finite_differences_of_the_ik(path):
    case = load_case(path)
    dev = case.device
    p0 = cube_points(case)[3]
    J = actuation_jacobian(dev, solve_legs(dev, p0[None]))[0]
    h = 1e-6
    cols = []
    dofs = range(3) if path == DELTA else range(6)
    for a in dofs:
        dp = np.zeros(6)
        dp[a] = h
        q = [np.array([s.q[0, leg.actuated_dof] for leg, s in zip(dev.legs, solve_legs(dev, np.array([p0 + sg * dp])).legs)])
             for sg in (1, -1)]
        cols.append((q[0] - q[1]) / (2 * h))
    # central differences: error O(h^2) ~ 1e-12 relative; 1e-7 allows the IK tolerance divided by h
    assert np.allclose(np.array(cols).T, J[:, list(dofs)], rtol=1e-6, atol=1e-6)


def test_hexapod_axial_legs_give_J_T_diag_k_J(hexapod):
    """Released joints make each strut a two-force member: K = J^T diag(k) J with k = E A / L (simplified)."""
    dev = hexapod.device
    P = _random_poses(hexapod, 20, 3)
    r = evaluate(dev, P, [3, -2, 10, 0.1, 0, -0.2], model="simplified", joints="released")
    J = actuation_jacobian(dev, r.state)
    link = dev.legs[0].links[0]
    length = np.stack([s.link_length[:, 0] for s in r.state.legs], axis=1)
    k = link.E * link.section.A / length
    K_closed = np.einsum("nia,ni,nib->nab", J, k, J)
    assert np.abs(r.K - K_closed).max() < CLOSED_FORM_RTOL * np.abs(K_closed).max()


def test_hexapod_detailed_released_closed_form(hexapod):
    """Detailed released: each strut's compliance is L/EA + drive + Hertz line along u + 1/k_Hertz(|f_i|), where
    f_i is the strut force of the closed form itself and k_Hertz = (6 E*^2 R* F)^(1/3)."""
    dev = hexapod.device
    P = _random_poses(hexapod, 10, 4)
    W = np.array([5.0, 3.0, -10.0, 0.2, -0.1, 0.05])
    r = evaluate(dev, P, W, model="detailed", joints="released")
    J = actuation_jacobian(dev, r.state)
    c = np.empty((len(P), 6))
    for i, (leg, s) in enumerate(zip(dev.legs, r.state.legs)):
        ln = leg.links[0]
        u = (s.C - leg.centres[0]) / s.link_length[:, :1]
        c_uc, c_ub, m = leg.hertz_line[0]
        zl = s.link_R[:, m, :, 2]
        c_line = c_uc + c_ub * np.einsum("ni,ni->n", u, zl) ** 2
        E, Rs, F_min = leg.hertz_point[2]
        f = r.leg_wrench[:, i, :3] @ np.zeros(3) + np.linalg.norm(r.leg_wrench[:, i, :3], axis=1)
        k_h = np.cbrt(6 * E**2 * Rs * np.maximum(f, F_min))
        c[:, i] = s.link_length[:, 0] / (ln.E * ln.section.A) + leg.drive_compliance + c_line + 1 / k_h
    K_closed = np.einsum("nia,ni,nib->nab", J, 1 / c, J)
    assert np.abs(r.K - K_closed).max() < CLOSED_FORM_RTOL * np.abs(K_closed).max()
    # and the strut forces are those of the closed form: f = k (J t)
    f_closed = (J @ r.twist[..., None])[..., 0] / c
    assert np.allclose(np.linalg.norm(r.leg_wrench[:, :, :3], axis=-1), np.abs(f_closed), rtol=1e-9)


def _random_rotation(seed):
    return rotvec_to_matrix(np.random.default_rng(seed).normal(size=3))


@pytest.mark.parametrize("path", [HEXAPOD, DELTA])
@pytest.mark.parametrize("joints", ["rigid", "released"])
def test_rotating_the_base_frame_rotates_K(path, joints):
    case = load_case(path)
    dev = case.device
    Q = _random_rotation(5)
    P = _random_poses(case, 5, 6, rotate=path == HEXAPOD)
    Pq = np.hstack([P[:, :3] @ Q.T, matrix_to_rotvec(Q @ rotvec_to_matrix(P[:, 3:]) @ Q.T)])
    W = np.array([2.0, -1.0, 8.0, 0.0, 0.1, 0.0])
    r = evaluate(dev, P, W, joints=joints)
    rq = evaluate(dev.rotated(Q), Pq, rot6(Q) @ W, joints=joints)
    K_expected = rot6(Q) @ r.K @ rot6(Q).T
    assert np.abs(rq.K - K_expected).max() < 1e-8 * np.abs(r.K).max()
    assert np.allclose(rq.contributions, r.contributions, rtol=1e-8)


@pytest.mark.parametrize("path", [HEXAPOD, DELTA])
def test_three_fold_symmetry(path):
    case = load_case(path)
    dev = case.device
    Rz = rotvec_to_matrix(np.array([0, 0, 2 * np.pi / 3]))
    P = _random_poses(case, 4, 7, rotate=False)
    Pq = P.copy()
    Pq[:, :3] = P[:, :3] @ Rz.T
    r, rq = evaluate(dev, P, None), evaluate(dev, Pq, None)
    assert np.abs(rq.K - rot6(Rz) @ r.K @ rot6(Rz).T).max() < 1e-8 * np.abs(r.K).max()


def test_delta_translational_stiffness_independent_derivation(delta):
    """With every link and pin made stiffer by a factor s, only the drives remain compliant; the platform
    translates only, so its translational compliance is J_x C J_x^T with J_x = (dq/dx)^-1 from finite
    differences of the inverse kinematics and C = diag(c_drive) (virtual work on three actuated joints)."""
    s = 1e11
    stiff = delta.with_params(**{"materials.aluminium.E_Pa": 70e9 * s, "materials.steel.E_Pa": 210e9 * s})
    dev = stiff.device
    for p0 in cube_points(delta)[[0, 3, 8]]:
        r = evaluate(dev, p0[None], None, model="detailed", joints="released")
        h = 1e-5
        Jq = np.empty((3, 3))
        for a in range(3):
            dp = np.zeros(6)
            dp[a] = h
            q = [np.array([st.q[0, leg.actuated_dof] for leg, st in zip(dev.legs, solve_legs(dev, np.array([p0 + sg * dp])).legs)])
                 for sg in (1, -1)]
            Jq[:, a] = (q[0] - q[1]) / (2 * h)
        Jx = np.linalg.inv(Jq)
        S_closed = Jx @ np.diag([leg.drive_compliance for leg in dev.legs]) @ Jx.T
        # two error sources, each measured by varying it alone: the stiffened links leave ~2e2/s of their
        # compliance (1.8e-5 at s = 1e7, 1.8e-7 at 1e9: it scales as 1/s), and the central differences ~2e-8 at
        # h = 1e-5 (1.8e-6 at h = 1e-4: it scales as h^2); measured here 1.8e-8
        assert np.abs(r.S[0, :3, :3] - S_closed).max() < 1e-7 * np.abs(S_closed).max()


def test_detailed_contributions_sum_to_one(hexapod, delta):
    for case in (hexapod, delta):
        r = evaluate(case.device, cube_points(case), [0, 0, 10, 0, 0, 0])
        assert np.allclose(r.contributions.sum(axis=1), 1.0, rtol=1e-9)


# -- friendly errors --------------------------------------------------------------------------------------


def _write(tmp_path, text):
    p = tmp_path / "dev.toml"
    p.write_text(text)
    return p


def _edited(path, old, new, count=1):
    text = path.read_text()
    assert old in text
    return text.replace(old, new, count)


#: (case file, text replaced, its replacement, the error the edited case must raise)
REFUSED_EDITS = {
    "names_the_leg_with_two_actuated_joints": (
        HEXAPOD, 'type = "U"\n  point_m = [0.115911, 0.031058', 'type = "R"\n  actuated = true\n  axes = [[0.0, 0.0, 1.0]]\n'
        '  drive = { law = "torsional", stiffness = 100.0 }\n  point_m = [0.115911, 0.031058',
        r"legs\[1\]\.joints: leg 1 \('b'\) has 2 actuated joints"),
    "names_the_leg_that_cannot_reach_the_cube": (
        DELTA, "cube_edge_m = 0.04", "cube_edge_m = 0.6", r"legs\[0\]: leg 0 \('leg1'\) cannot reach test point P1"),
    "names_the_joint_key": (
        HEXAPOD, 'type = "P"\n  actuated = true', 'type = "P"\n  point_m = [0.0, 0.0, 0.1]\n  actuated = true',
        r"legs\[0\]\.joints\[1\]\.point_m: a P joint has no centre"),
    "names_wrong_link_count": (
        DELTA, '  [[legs.links]]\n  name = "rod"', '  [[legs.links]]\n  name = "extra"\n  element = "rigid"\n\n  [[legs.links]]\n  name = "rod"',
        r"legs\[0\]\.links: leg 0 \('leg'\) has 3 links; expected 2"),
    # platform U's outer axis no longer parallel to the crank axis: no leg carries a couple, the platform turns
    "names_a_free_platform_motion": (
        DELTA, "axes = [[0.661438, 0.0, -0.75], [0.0, 1.0, 0.0]]", "axes = [[0.661438, 0.0, -0.75], [0.75, 0.0, 0.661438]]",
        "free to move"),
}


@pytest.mark.parametrize("edit", REFUSED_EDITS)
def test_error(edit, tmp_path):
    path, old, new, message = REFUSED_EDITS[edit]
    bad = _edited(path, old, new)
    with pytest.raises(CaseError, match=message):
        load_case(_write(tmp_path, bad))


def test_with_params_reaches_a_leg_entry(delta):
    """A design variant of one link by its index in the [[legs]] array (every symmetric copy follows)."""
    thick = delta.with_params(**{"legs.0.links.1.outer_diameter_m": 0.010})
    assert thick.legs[0].links[1].outer_diameter_m == 0.010 and delta.legs[0].links[1].outer_diameter_m == 0.008
    P = cube_points(delta)
    assert np.all(evaluate(thick.device, P, None).directional_stiffness([1, 0, 0])
                  > evaluate(delta.device, P, None).directional_stiffness([1, 0, 0]))
    with pytest.raises(CaseError, match="index 3 out of range"):
        delta.with_params(**{"legs.3.links.1.outer_diameter_m": 0.010})
    with pytest.raises(CaseError, match=r"legs\[0\]\.links\[1\]\.inner_diameter_m"):
        delta.with_params(**{"legs.0.links.1.outer_diameter_m": 0.005})


def test_unreachable_pose_names_the_leg(delta):
    from femcheck.errors import UnreachablePoseError
    with pytest.raises(UnreachablePoseError, match=r"unreachable by chain \(leg\) 0: no inverse-kinematics solution of leg 'leg1'"):
        evaluate(delta.device, [0.0, 0.0, -0.5, 0, 0, 0])


def test_element_scale_locates_an_effect_by_leg_and_element(hexapod):
    dev = hexapod.device
    P = cube_points(hexapod)
    W = [0, 0, 10, 0, 0, 0]
    # twice every compliance: half the stiffness (the Hertz linearization force does not change)
    assert np.allclose(evaluate(dev, P, W, element_scale=2.0).K, evaluate(dev, P, W).K / 2, rtol=1e-10)
    # strut 2 three times softer: the closed form J^T diag(k) J with k_2 / 3 (simplified, released)
    scale = np.ones((6, len(dev.element_names)))
    scale[2, dev.element_names.index("strut")] = 3.0
    r = evaluate(dev, P, W, model="simplified", joints="released", element_scale=scale)
    J = actuation_jacobian(dev, r.state)
    link = dev.legs[0].links[0]
    k = link.E * link.section.A / np.stack([s.link_length[:, 0] for s in r.state.legs], axis=1)
    k[:, 2] /= 3.0
    K_closed = np.einsum("nia,ni,nib->nab", J, k, J)
    assert np.abs(r.K - K_closed).max() < CLOSED_FORM_RTOL * np.abs(K_closed).max()


def test_error_symmetry_needs_the_home_pose_on_the_axis(tmp_path):
    bad = _edited(HEXAPOD, "home_pose = [0.0, 0.0, 0.18, 0.0, 0.0, 0.0]", "home_pose = [0.01, 0.0, 0.18, 0.0, 0.0, 0.0]")
    with pytest.raises(CaseError, match=r"symmetry\.copies: copies = 3 needs the home pose on the base z axis"):
        load_case(_write(tmp_path, bad))


def test_error_clamp_only_first(tmp_path):
    import re
    text = re.sub(r'type = "U"\n  point_m = \[0\.18, 0\.0, 0\.0\]\n  axes = .*\n  hertz_line = .*\n',
                  'type = "F"\n  point_m = [0.18, 0.0, 0.0]\n', DELTA.read_text())
    assert 'type = "F"' in text
    with pytest.raises(CaseError, match=r"legs\[0\]\.joints: leg 0 \('leg'\): an F \(clamp\) joint can only be the first"):
        load_case(_write(tmp_path, text))
    # a joint law on a joint that cannot carry it is named at the joint's key
    bad = _edited(HEXAPOD, 'type = "S"\n  point_m = [0.042426, -0.042426, 0.18]', 'type = "U"\n  point_m = [0.042426, -0.042426, 0.18]')
    with pytest.raises(CaseError, match=r"legs\[0\]\.joints\[2\]\.hertz_point: only on an S joint"):
        load_case(_write(tmp_path, bad))
