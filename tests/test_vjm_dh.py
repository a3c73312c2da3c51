"""DH forward kinematics and geometric Jacobian (femcheck.vjm.dh): closed forms and finite differences."""
import numpy as np
import pytest

from femcheck.kinematics.frames import matrix_to_rotvec
from femcheck.vjm.dh import DHChain, forward_kinematics, geometric_jacobian

L1, L2 = 0.4, 0.3


def planar_2r(convention):
    if convention == "standard":
        return DHChain(a_m=(L1, L2), alpha_rad=(0.0, 0.0), d_m=(0.0, 0.0), theta_offset_rad=(0.0, 0.0))
    # modified: a_{i-1} in row i, the last link length becomes the tool offset
    return DHChain(a_m=(0.0, L1), alpha_rad=(0.0, 0.0), d_m=(0.0, 0.0), theta_offset_rad=(0.0, 0.0),
                   convention="modified", tool_offset_m=(L2, 0.0, 0.0))


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_planar_2r_matches_closed_form(convention):
    q = np.random.default_rng(1).uniform(-np.pi, np.pi, (50, 2))
    c1, s1 = np.cos(q[:, 0]), np.sin(q[:, 0])
    c12, s12 = np.cos(q.sum(1)), np.sin(q.sum(1))
    fk = forward_kinematics(planar_2r(convention), q)
    # 1e-12 m: double-precision round-off of sums of products of sines and cosines of O(1) m lengths
    np.testing.assert_allclose(fk.tcp[:, 0], L1 * c1 + L2 * c12, atol=1e-12)
    np.testing.assert_allclose(fk.tcp[:, 1], L1 * s1 + L2 * s12, atol=1e-12)
    np.testing.assert_allclose(fk.tcp[:, 2], 0.0, atol=1e-12)
    J = geometric_jacobian(planar_2r(convention), q)
    Jref = np.zeros((50, 6, 2))
    Jref[:, 0] = np.stack([-L1 * s1 - L2 * s12, -L2 * s12], -1)
    Jref[:, 1] = np.stack([L1 * c1 + L2 * c12, L2 * c12], -1)
    Jref[:, 5] = 1.0
    # same round-off argument as above
    np.testing.assert_allclose(J, Jref, atol=1e-12)


def random_chain(rng, convention, n=6):
    return DHChain(a_m=tuple(rng.uniform(-0.4, 0.4, n)), alpha_rad=tuple(rng.uniform(-np.pi, np.pi, n)),
                   d_m=tuple(rng.uniform(-0.4, 0.4, n)), theta_offset_rad=tuple(rng.uniform(-np.pi, np.pi, n)),
                   convention=convention, tool_offset_m=tuple(rng.uniform(-0.1, 0.1, 3)))


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_jacobian_matches_finite_differences(convention):
    rng = np.random.default_rng(7)
    for _ in range(5):
        chain = random_chain(rng, convention, n=int(rng.integers(2, 8)))
        q = rng.uniform(-np.pi, np.pi, (4, chain.n_joints))
        J = geometric_jacobian(chain, q)
        h = 1e-6
        for i in range(chain.n_joints):
            dq = np.zeros(chain.n_joints)
            dq[i] = h
            fp, fm = forward_kinematics(chain, q + dq), forward_kinematics(chain, q - dq)
            v = (fp.tcp - fm.tcp) / (2 * h)
            Rp, Rm = fp.frames[:, -1, :3, :3], fm.frames[:, -1, :3, :3]
            w = matrix_to_rotvec(Rp @ np.swapaxes(Rm, -1, -2)) / (2 * h)
            # central differences: truncation O(h^2) ~ 1e-12 plus round-off eps/h ~ 1e-10 on O(1) lengths
            np.testing.assert_allclose(J[:, :3, i], v, atol=1e-8)
            np.testing.assert_allclose(J[:, 3:, i], w, atol=1e-8)


def test_standard_and_modified_tables_of_the_same_arm_agree():
    """KUKA LBR iiwa 7: standard DH (cases/cobot7.toml) and its Craig form give the same TCP and Jacobian."""
    d2r = np.deg2rad
    std = DHChain(a_m=(0.0,) * 7, alpha_rad=tuple(d2r([-90, 90, 90, -90, -90, 90, 0])),
                  d_m=(0.34, 0, 0.4, 0, 0.4, 0, 0.126), theta_offset_rad=(0.0,) * 7)
    mod = DHChain(a_m=(0.0,) * 7, alpha_rad=tuple(d2r([0, -90, 90, 90, -90, -90, 90])),
                  d_m=(0.34, 0, 0.4, 0, 0.4, 0, 0.0), theta_offset_rad=(0.0,) * 7, convention="modified",
                  tool_offset_m=(0.0, 0.0, 0.126))
    q = np.random.default_rng(3).uniform(-2, 2, (20, 7))
    # identical geometry, so only round-off (~1e-15 m) separates the two
    np.testing.assert_allclose(forward_kinematics(std, q).tcp, forward_kinematics(mod, q).tcp, atol=1e-12)
    np.testing.assert_allclose(geometric_jacobian(std, q), geometric_jacobian(mod, q), atol=1e-12)


def test_irb120_home_position_and_wrist_singularity():
    from femcheck.case import load_case

    case = load_case("cases/irb120.toml")
    fk = forward_kinematics(case.chain, np.zeros(6))
    # ABB product specification: flange centre at (374, 0, 630) mm at the home posture; exact DH sums
    np.testing.assert_allclose(fk.tcp[0], [0.374, 0.0, 0.630], atol=1e-12)
    # seed 003 Table 6: postures 1 and 3 have theta5 = 0 (axes 4 and 6 aligned) -> rank 5; posture 2 is regular
    q = np.deg2rad([[0, 0, 0, 0, 0, 0], [0, 45, -45, -45, 45, 0], [20, 20, -30, 0, 0, 0]])
    J = geometric_jacobian(case.chain, q)
    assert [int(np.linalg.matrix_rank(Ji, tol=1e-9)) for Ji in J] == [5, 6, 5]


def test_bad_pose_width_is_rejected():
    with pytest.raises(ValueError, match=r"expected \(m, 2\)"):
        forward_kinematics(planar_2r("standard"), np.zeros(3))
