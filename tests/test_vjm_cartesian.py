"""Cartesian compliance/stiffness and the complementary stiffness K_C (femcheck.vjm.cartesian_stiffness)."""
import numpy as np
import pytest

from femcheck.kinematics.frames import rotvec_to_matrix
from femcheck.vjm.cartesian_stiffness import (cartesian_compliance, cartesian_stiffness, complementary_stiffness,
                                              deflection)
from femcheck.vjm.dh import DHChain, forward_kinematics, screw_jacobian

L1, L2 = 0.4, 0.3


def test_planar_2r_compliance_and_kc_closed_form():
    chain = DHChain(a_m=(L1, L2), alpha_rad=(0.0, 0.0), d_m=(0.0, 0.0), theta_offset_rad=(0.0, 0.0))
    k1, k2 = 2.0e4, 8.0e3
    q = np.random.default_rng(2).uniform(-np.pi, np.pi, (30, 2))
    F = np.array([12.0, -7.0, 0.0, 0.0, 0.0, 0.0])
    c1, s1 = np.cos(q[:, 0]), np.sin(q[:, 0])
    c12, s12 = np.cos(q.sum(1)), np.sin(q.sum(1))
    px, py = L1 * c1 + L2 * c12, L1 * s1 + L2 * s12
    # closed form: tau1 = -Fx py + Fy px, tau2 = L2 (-Fx s12 + Fy c12); dX = J diag(1/k) tau
    t1, t2 = -F[0] * py + F[1] * px, L2 * (-F[0] * s12 + F[1] * c12)
    dx = -py * t1 / k1 - L2 * s12 * t2 / k2
    dy = px * t1 / k1 + L2 * c12 * t2 / k2
    fk = forward_kinematics(chain, q)
    J = screw_jacobian(fk.axes, fk.origins, fk.tcp)
    res = deflection(J, [k1, k2], F)
    # round-off only (products of O(1) numbers, results ~1e-4 m)
    np.testing.assert_allclose(res.twist[:, 0], dx, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(res.twist[:, 1], dy, rtol=1e-12, atol=1e-18)
    # K_C = d(J^T F)/dtheta: [[-(p.F), -L2 e12.F], [-L2 e12.F, -L2 e12.F]] with e12 = (c12, s12)
    pF = px * F[0] + py * F[1]
    eF = L2 * (c12 * F[0] + s12 * F[1])
    KC_ref = -np.stack([np.stack([pF, eF], -1), np.stack([eF, eF], -1)], -2)
    KC = complementary_stiffness(fk.axes, fk.origins, fk.tcp, F)
    # round-off only
    np.testing.assert_allclose(KC, KC_ref, atol=1e-12)


def _jacobian_of_virtual_chain(axes0, origins0, p0, delta):
    """Rigid-body FK of an ordered chain of revolute virtual joints (product of exponentials), then its Jacobian."""
    axes, origins, p = axes0.copy(), origins0.copy(), p0.copy()
    k = axes.shape[0]
    for i in reversed(range(k)):                       # joint i moves everything after it
        R = rotvec_to_matrix(axes[i] * delta[i])
        o = origins[i]
        axes[i + 1:] = axes[i + 1:] @ R.T
        origins[i + 1:] = (origins[i + 1:] - o) @ R.T + o
        p = (p - o) @ R.T + o
    return screw_jacobian(axes[None], origins[None], p[None])[0]


@pytest.mark.parametrize("extended", [False, True])
def test_kc_matches_finite_difference_of_JT_F(extended):
    from femcheck.vjm.extended_vjm import virtual_joint_axes

    rng = np.random.default_rng(11)
    for convention in ("standard", "modified"):
        chain = DHChain(a_m=tuple(rng.uniform(-0.4, 0.4, 6)), alpha_rad=tuple(rng.uniform(-3, 3, 6)),
                        d_m=tuple(rng.uniform(-0.4, 0.4, 6)), theta_offset_rad=tuple(rng.uniform(-3, 3, 6)),
                        convention=convention, tool_offset_m=(0.02, -0.05, 0.1))
        fk = forward_kinematics(chain, rng.uniform(-np.pi, np.pi, (1, 6)))
        axes, origins = virtual_joint_axes(fk, extended, tilt_offset_m=rng.uniform(0, 0.1, 6))
        W = np.concatenate([rng.normal(0, 30, 3), rng.normal(0, 5, 3)])
        KC = complementary_stiffness(axes, origins, fk.tcp, W)[0]
        k = axes.shape[1]
        h = 1e-6
        fd = np.empty((k, k))
        for i in range(k):
            dp, dm = np.zeros(k), np.zeros(k)
            dp[i], dm[i] = h, -h
            Jp = _jacobian_of_virtual_chain(axes[0], origins[0], fk.tcp[0], dp)
            Jm = _jacobian_of_virtual_chain(axes[0], origins[0], fk.tcp[0], dm)
            fd[:, i] = (Jp - Jm).T @ W / (2 * h)
        # central differences: O(h^2) truncation plus eps |J^T F| / h ~ 1e-9 N m/rad on entries of ~10 N m/rad
        np.testing.assert_allclose(KC, fd, atol=1e-7 * max(1.0, np.abs(KC).max()))
        # without moments K_C of a conventional chain is a Hessian of F.p(theta): symmetric
        if not extended:
            KCf = complementary_stiffness(axes, origins, fk.tcp, np.r_[W[:3], 0, 0, 0])[0]
            np.testing.assert_allclose(KCf, KCf.T, atol=1e-12 * np.abs(KCf).max())


def test_stiffness_equals_seed_002_eq5_for_square_jacobian():
    from femcheck.case import load_case

    case = load_case("cases/irb120.toml")
    q = np.deg2rad([[0, 45, -45, -45, 45, 0], [10, 30, -20, 40, 70, -30]])
    W = np.array([29.43, -10.0, 5.0, 1.0, -2.0, 0.5])
    fk = forward_kinematics(case.chain, q)
    J = screw_jacobian(fk.axes, fk.origins, fk.tcp)
    KC = complementary_stiffness(fk.axes, fk.origins, fk.tcp, W)
    Kt = np.diag(case.joint_stiffness)
    Jinv = np.linalg.inv(J)
    K_eq5 = np.swapaxes(Jinv, -1, -2) @ (Kt - KC) @ Jinv      # seed 002 eq. 5 literally
    K, rank = cartesian_stiffness(cartesian_compliance(J, case.joint_stiffness, KC))
    assert list(rank) == [6, 6]
    # two algebraically equal routes; cond(J) ~ 1e2 loses ~2 digits of 1e-16
    np.testing.assert_allclose(K, K_eq5, rtol=1e-9, atol=1e-9 * np.abs(K_eq5).max())


def test_symmetry_of_home_posture_and_singular_rank():
    from femcheck.case import load_case
    from femcheck.vjm.serial_vjm import deflect

    model = load_case("cases/irb120.toml").vjm()
    res = deflect(model, np.zeros((1, 6)), [0.0, 29.43, 0.0, 0.0, 0.0, 0.0], complementary=False)
    # at q = 0 the arm lies in the x-z plane: a force along y gives no x or z displacement (mirror symmetry);
    # tolerance = round-off of cos(90 deg) ~ 6e-17 times lengths and compliances
    np.testing.assert_allclose(res.twist[0, [0, 2]], 0.0, atol=1e-15)
    assert res.twist[0, 1] > 0
    assert res.rank[0] == 5
    # the pseudo-inverse stiffness reproduces the deflection from the wrench in the range of C
    np.testing.assert_allclose(res.C[0] @ res.K[0] @ res.twist[0], res.twist[0], rtol=1e-8, atol=1e-15)


def test_kc_changes_deflection_only_slightly_for_seed_003_loads():
    """Seed 003 sec. 2.3 neglects K_C because its effect is small away from singularities: check it stays < 1 %."""
    from femcheck.case import load_case
    from femcheck.vjm.serial_vjm import deflect

    model = load_case("cases/irb120.toml").vjm()
    q = np.deg2rad([[0, 45, -45, -45, 45, 0]])
    for F in np.eye(3) * 29.43:
        W = np.r_[F, 0, 0, 0]
        a = deflect(model, q, W, complementary=False).twist[0, :3]
        b = deflect(model, q, W, complementary=True).twist[0, :3]
        # 29.43 N on a ~0.5 m lever against ~1e4 N m/rad joints: K_C/K_theta ~ 1e-3
        assert np.linalg.norm(a - b) < 0.01 * np.linalg.norm(a)
        assert np.linalg.norm(a - b) > 0


def test_kc_gives_the_tangent_stiffness_of_the_loaded_equilibrium():
    """Seed 002 eq. 4 physically: at the equilibrium K_theta (theta - theta0) = J(theta)^T F of a heavily loaded
    arm, a small extra wrench dF moves the tool by J (K_theta - K_C)^-1 J^T dF, and not by J K_theta^-1 J^T dF."""
    from femcheck.case import load_case
    from femcheck.kinematics.frames import matrix_to_rotvec

    case = load_case("cases/irb120.toml")
    chain, k = case.chain, case.joint_stiffness / 50.0          # soft joints: the load bends the arm by ~10 deg
    q0 = np.deg2rad([10, 40, -30, 20, 60, -10])
    F = np.array([200.0, -150.0, -300.0, 10.0, -5.0, 8.0])

    def parts(q):
        fk = forward_kinematics(chain, q[None])
        J = screw_jacobian(fk.axes, fk.origins, fk.tcp)[0]
        return fk, J, complementary_stiffness(fk.axes, fk.origins, fk.tcp, F_now)[0]

    def equilibrium(Fw):
        nonlocal F_now
        F_now = Fw
        q = q0.copy()
        for _ in range(50):                                      # Newton on K (q - q0) - J(q)^T F = 0
            fk, J, KC = parts(q)
            r = k * (q - q0) - J.T @ Fw
            q = q - np.linalg.solve(np.diag(k) - KC, r)
            if np.abs(r).max() < 1e-12:
                break
        return q

    F_now = F
    q1 = equilibrium(F)
    assert np.rad2deg(np.abs(q1 - q0)).max() > 0.5               # the load really bends the arm
    dF = np.array([1.0, 2.0, -1.5, 0.1, 0.2, -0.1])
    eps = 1e-3
    q2 = equilibrium(F + eps * dF)
    f1, f2 = forward_kinematics(chain, q1[None]), forward_kinematics(chain, q2[None])
    dX = np.r_[(f2.tcp - f1.tcp)[0], matrix_to_rotvec(f2.frames[0, -1, :3, :3] @ f1.frames[0, -1, :3, :3].T)] / eps
    F_now = F
    _, J, KC = parts(q1)
    with_kc = cartesian_compliance(J[None], k, KC[None])[0] @ dF
    without = cartesian_compliance(J[None], k)[0] @ dF
    # forward difference with eps = 1e-3 of a smooth map: O(eps) relative error ~1e-4 of the response
    np.testing.assert_allclose(dX, with_kc, rtol=0, atol=2e-4 * np.abs(with_kc).max())
    assert np.abs(dX - without).max() > 10 * np.abs(dX - with_kc).max()
