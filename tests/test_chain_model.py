"""The 6-PSU compliance-chain model against the reference numbers, two independent formulations
(seed 001 passive-joint elimination, a direct-stiffness frame model) and invariants."""
from __future__ import annotations

import numpy as np
import pytest

import femcheck
from femcheck.chain import ChainAdjustments, chain_element_compliances, device_parameters, evaluate
from femcheck.kinematics.frames import guideway_frames, link_frames
from femcheck.compliance import cantilever_compliance
from femcheck.kinematics import psu6
from femcheck.kinematics.frames import rot6, twist_shift

X, Y, Z = (np.eye(6)[k] * 15.0 for k in range(3))


# ----------------------------------------------------------------------------- reference numbers
@pytest.mark.parametrize("joints, expected", [("rigid", (0.2662, 0.2660, 0.0661)), ("released", (0.7179, 0.7173, 0.0729))])
def test_P0_deflections_match_reference(case, points, joints, expected):
    got = [evaluate(case, points[:1], W, joints=joints).twist[0, k] * 1e3 for k, W in enumerate((X, Y, Z))]
    # docs/conventions.md quotes 4 decimals in mm: half a unit in the last place
    assert got == pytest.approx(expected, abs=5e-5)


@pytest.mark.parametrize("joints, mean, mx", [("rigid", (38.3, 38.2, 73.2), (45, 45, 80)),
                                              ("released", (56.6, 56.2, 70.4), (68, 68, 81))])
def test_simplified_vs_detailed_errors_match_reference(case, points, joints, mean, mx):
    errs = []
    for k, W in enumerate((X, Y, Z)):
        d = evaluate(case, points, W, model="detailed", joints=joints).twist[:, k]
        s = evaluate(case, points, W, model="simplified", joints=joints).twist[:, k]
        errs.append(100 * np.abs(s - d) / np.abs(d))
    # quoted to 0.1 % (means) and to whole percent (max; 67.5 is printed as 68)
    assert [e.mean() for e in errs] == pytest.approx(mean, abs=0.051)
    assert [e.max() for e in errs] == pytest.approx(mx, abs=0.6)


@pytest.mark.parametrize("joints, shares", [("rigid", (31.1, 29.3, 7.5, 26.6, 5.5)), ("released", (37.5, 44.2, 8.5, 1.4, 8.3))])
def test_mean_contributions_match_reference(case, points, joints, shares):
    c = np.vstack([evaluate(case, points, W, joints=joints).contributions for W in (X, Y, Z)])
    assert np.allclose(c.sum(1), 1.0, atol=1e-12) and (c >= -1e-15).all()   # energy shares: exact partition
    assert 100 * c.mean(0) == pytest.approx(shares, abs=0.051)              # quoted to 0.1 %


# ----------------------------------------------------------------------------- independent formulations
def _joint_twists(legs, k):
    """(6, 6, 5) unit twists at C_i of the S-joint (3) and U-joint (2) rotations of pose k."""
    out = np.zeros((6, 6, 5))
    for i in range(6):
        r = legs.C[k, i] - legs.B[k, i]
        for j, w in enumerate(np.eye(3)):
            out[i, :, j] = np.concatenate([np.cross(w, r), w])
        a1 = np.cross([0, 0, 1.0], legs.u[k, i])
        a1 /= np.linalg.norm(a1)
        a2 = np.cross(legs.u[k, i], a1)
        out[i, 3:, 3], out[i, 3:, 4] = a1, a2
    return out


@pytest.mark.parametrize("model", ["simplified", "detailed"])
def test_released_equals_passive_joint_elimination_seed001(case, points, model):
    """K_i = upper-left block of [[S_C,i, Jp],[Jp^T, 0]]^-1 (seed 001 eqs. 5-6), summed at the TCP."""
    r = evaluate(case, points, X, model=model, joints="released")
    S = chain_element_compliances(case, points, r.k_sp if model == "detailed" else None, model=model).sum(axis=2)
    legs = psu6.leg_geometry(case, points)
    for k in range(len(points)):
        Jp = _joint_twists(legs, k)
        KT = np.zeros((6, 6))
        for i in range(6):
            big = np.block([[S[k, i], Jp[i]], [Jp[i].T, np.zeros((5, 5))]])
            Ki = np.linalg.inv(big)[:6, :6]
            assert np.linalg.matrix_rank(Ki, tol=1e-9 * np.abs(Ki).max()) == 1   # a two-force member
            G = twist_shift(legs.C[k, i] - legs.tcp[k])
            KT += G.T @ Ki @ G
        # two formulations, same algebra: round-off of a bordered 11x11 inverse
        assert np.abs(KT - r.K[k]).max() < 1e-8 * np.abs(r.K[k]).max()


def _beam_tip_stiffness(L, E, G, sec):
    return np.linalg.inv(cantilever_compliance(L, E, G, sec))


@pytest.mark.parametrize("model", ["simplified", "detailed"])
def test_rigid_equals_direct_stiffness_frame_model(case, points, model):
    """Welded-joint frame: guideway and link beam elements, joint springs on translations with tied
    rotations, platform node T, assembled and condensed to T; compared with the chain-sum model."""
    r = evaluate(case, points, Y, model=model, joints="rigid")
    p = device_parameters(case)
    legs = psu6.leg_geometry(case, points)
    R_lg = guideway_frames(case)
    e = legs.e
    detailed = model == "detailed"
    for k in range(len(points)):
        n_dof = 6 + 6 * 12          # T (6) + per leg: B1 (6), B2 translation (3), C_link translation (3)
        K = np.zeros((n_dof, n_dof))
        R_B = link_frames(legs.u[k])
        for i in range(6):
            o = 6 + 12 * i
            I_B1 = np.zeros((6, n_dof)); I_B1[:, o:o + 6] = np.eye(6)
            G = twist_shift(legs.C[k, i] - legs.tcp[k])
            I_Cp = np.zeros((6, n_dof)); I_Cp[:, :6] = G            # platform attachment point C_i
            if detailed:
                I_B2 = np.zeros((6, n_dof)); I_B2[:3, o + 6:o + 9] = np.eye(3); I_B2[3:] = I_B1[3:]
                I_Cl = np.zeros((6, n_dof)); I_Cl[:3, o + 9:o + 12] = np.eye(3); I_Cl[3:] = I_Cp[3:]
            else:   # no joint elements: the link is welded to slider and platform
                I_B2, I_Cl = I_B1, I_Cp
            # guideway: clamped at A, tip B1
            Kg = rot6(R_lg[i]) @ _beam_tip_stiffness(legs.slider[k, i], p.E_lg, p.G_lg, p.lg_section) @ rot6(R_lg[i]).T
            K += I_B1.T @ Kg @ I_B1
            # proximal link from B2 to C_link: energy of the relative twist t_C - Jf(C-B)^T t_B
            D = I_Cl - twist_shift(legs.C[k, i] - legs.B[k, i]) @ I_B2
            Kp = rot6(R_B[i]) @ _beam_tip_stiffness(p.L2, p.E_prox, p.G_prox, p.prox_section) @ rot6(R_B[i]).T
            K += D.T @ Kp @ D
            if detailed:
                c_t = p.c_act * np.outer(e, e) + np.eye(3) / r.k_sp[k, i]      # actuation + Hertz, in series
                Dt = (I_B2 - I_B1)[:3]
                K += Dt.T @ np.linalg.inv(c_t) @ Dt
                S_uj = R_B[i] @ np.diag([p.c_uc, p.c_uc, p.c_uc + p.c_ub]) @ R_B[i].T
                Du = (I_Cl - I_Cp)[:3]
                K += Du.T @ np.linalg.inv(S_uj) @ Du
        if not detailed:   # B2 and C_link translations are not used without joint elements
            unused = [6 + 12 * i + j for i in range(6) for j in range(6, 12)]
            K[unused, unused] = 1.0
        KTT, KTx, Kxx = K[:6, :6], K[:6, 6:], K[6:, 6:]
        KT = KTT - KTx @ np.linalg.solve(Kxx, KTx.T)
        # condensation of a 78-DOF system with stiffness ratios ~1e6: 1e-7 relative is round-off
        assert np.abs(KT - r.K[k]).max() < 1e-7 * np.abs(r.K[k]).max()


def test_single_guideway_cantilever_gives_3EI_over_L3(case, points):
    legs = psu6.leg_geometry(case, points[:1])
    S = chain_element_compliances(case, points[:1], model="simplified")[0, :, 0]   # guideway element at C_i
    p = device_parameters(case)
    for i in range(6):
        back = twist_shift(legs.B[0, i] - legs.C[0, i])     # twist at C -> twist at B
        S_B = back @ S[i] @ back.T
        x_A, y_A, _ = guideway_frames(case)[i].T
        L = legs.slider[0, i]
        # Euler-Bernoulli closed form, exact to round-off
        assert x_A @ S_B[:3, :3] @ x_A == pytest.approx(L**3 / (3 * p.E_lg * p.lg_section.Iy), rel=1e-12)
        assert y_A @ S_B[:3, :3] @ y_A == pytest.approx(L**3 / (3 * p.E_lg * p.lg_section.Ix), rel=1e-12)


def test_series_elements_add_compliances(case, points):
    """The detailed chain compliance is the sum of its elements: doubling one element's compliance adds
    exactly that element once more (linear in the element compliances at fixed Hertz stiffness)."""
    r = evaluate(case, points, Z, model="detailed")
    S1 = chain_element_compliances(case, points, r.k_sp)
    scale = np.ones((6, 5)); scale[:, 3] = 2.0
    S2 = chain_element_compliances(case, points, r.k_sp, adjust=ChainAdjustments(element_scale=scale))
    assert np.abs(S2.sum(2) - S1.sum(2) - S1[:, :, 3]).max() < 1e-14 * np.abs(S1).max()


# ----------------------------------------------------------------------------- invariants
@pytest.mark.parametrize("joints", ["rigid", "released"])
@pytest.mark.parametrize("model", ["simplified", "detailed"])
def test_stiffness_symmetric_positive_definite(case, joints, model):
    rng = np.random.default_rng(7)
    poses = np.tile(femcheck.test_points(case)[0], (200, 1))
    poses[:, :3] += rng.uniform(-0.03, 0.03, (200, 3))
    poses[:, 3:] = rng.uniform(-0.1, 0.1, (200, 3))
    K = evaluate(case, poses, X, model=model, joints=joints).K
    assert np.abs(K - K.swapaxes(1, 2)).max() <= 1e-12 * np.abs(K).max()
    assert (np.linalg.eigvalsh(K) > 0).all()


@pytest.mark.parametrize("joints", ["rigid", "released"])
def test_120_degree_symmetry_rotates_K(case, points, joints):
    """Rotating the load case by 120 deg about z maps the device onto itself: K(Rp) = Rot(R) K(p) Rot(R)^T."""
    c, s = np.cos(2 * np.pi / 3), np.sin(2 * np.pi / 3)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    p = points[[1, 6]].copy()
    pr = p.copy()
    pr[:, :3] = p[:, :3] @ R.T
    W = np.array([15.0, 4.0, -3.0, 0, 0, 0])
    a = evaluate(case, p, W, joints=joints)
    b = evaluate(case, pr, rot6(R) @ W, joints=joints)
    assert np.abs(b.K - rot6(R) @ a.K @ rot6(R).T).max() < 1e-9 * np.abs(a.K).max()   # round-off of trig + inverses
    assert np.abs(b.twist - a.twist @ rot6(R).T).max() < 1e-9 * np.abs(a.twist).max()


@pytest.mark.parametrize("joints", ["rigid", "released"])
def test_cube_centre_is_laterally_isotropic(case, points, joints):
    K = evaluate(case, points[:1], None, model="simplified", joints=joints).K[0]
    # 3-fold symmetry: Kxx = Kyy and Kxy = 0 (round-off only)
    assert K[0, 0] == pytest.approx(K[1, 1], rel=1e-10)
    assert abs(K[0, 1]) < 1e-10 * K[0, 0]


def test_compiled_kernel_equals_numpy_reference(case):
    rng = np.random.default_rng(11)
    n = 300
    poses = np.tile(femcheck.test_points(case)[0], (n, 1))
    poses[:, :3] += rng.uniform(-0.025, 0.025, (n, 3))
    poses[:, 3:] = rng.uniform(-0.05, 0.05, (n, 3))
    W = rng.normal(size=(n, 6)) * [15, 15, 15, 0.3, 0.3, 0.3]
    adjust = ChainAdjustments(element_scale=rng.uniform(0.5, 2.0, (6, 5)), joint_rotation_compliance=1e-3)
    for joints in ("rigid", "released"):
        for model in ("simplified", "detailed"):
            for adj in (None, adjust if joints == "rigid" else ChainAdjustments(element_scale=adjust.element_scale)):
                a = evaluate(case, poses, W, model=model, joints=joints, adjust=adj, backend="numpy")
                b = evaluate(case, poses, W, model=model, joints=joints, adjust=adj, backend="compiled")
                for name in ("K", "twist", "chain_wrench", "element_energy"):
                    x, y = getattr(a, name), getattr(b, name)
                    # same equations, different operation order: 1e-10 relative
                    assert np.abs(x - y).max() <= 1e-10 * np.abs(x).max(), (joints, model, name)


def test_batched_equals_one_pose_at_a_time(case, points):
    batch = evaluate(case, points, X).twist
    single = np.vstack([evaluate(case, points[k:k + 1], X).twist for k in range(9)])
    assert np.abs(batch - single).max() == 0.0   # no coupling between poses


def test_hertz_linearization_is_a_fixed_point(case, points):
    """Each spherical joint's stiffness is k_sp(F) at the force its own chain carries (docs/conventions.md §6)."""
    r = evaluate(case, points, X, model="detailed")
    p = device_parameters(case)
    F = np.maximum(np.linalg.norm(r.chain_wrench[..., :3], axis=-1), p.F_min_sp)
    k = np.cbrt(6 * p.E_star_sp**2 * p.R_star_sp * F)
    assert np.abs(k - r.k_sp).max() < 1e-11 * k.max()


def test_joint_rotation_springs_interpolate_rigid_and_released(case, points):
    rigid = evaluate(case, points, X, model="simplified", joints="rigid").twist[:, 0]
    released = evaluate(case, points, X, model="simplified", joints="released").twist[:, 0]
    mid = evaluate(case, points, X, model="simplified", adjust=ChainAdjustments(joint_rotation_compliance=1e-2)).twist[:, 0]
    soft = evaluate(case, points, X, model="simplified", adjust=ChainAdjustments(joint_rotation_compliance=1e4)).twist[:, 0]
    assert (rigid < mid).all() and (mid < released).all()
    # a very soft torsional spring (1e4 rad/(N m)) behaves as a free joint: 1e-4 relative
    assert soft == pytest.approx(released, rel=1e-4)


def test_public_api_shapes_and_units(case, points):
    t = femcheck.deflection(case, points, [15, 0, 0, 0, 0, 0])
    K = femcheck.stiffness(case, points, wrench=[15, 0, 0, 0, 0, 0])
    c = femcheck.contributions(case, points, [15, 0, 0, 0, 0, 0])
    assert t.shape == (9, 6) and K.shape == (9, 6, 6)
    assert set(c) == {"guideway", "actuation", "spherical_joint", "proximal_link", "universal_joint"}
    assert np.abs(np.einsum("nij,nj->ni", K, t) - [15, 0, 0, 0, 0, 0]).max() < 1e-9   # K t = W
    Ks = femcheck.stiffness(case, points[:1], model="detailed", wrench=None)   # unloaded: joints at F_min
    assert (np.linalg.eigvalsh(Ks) > 0).all()


@pytest.mark.parametrize("joints", ["rigid", "released"])
def test_mirror_symmetry_about_the_xz_plane(case, points, joints):
    """The device is symmetric under y -> -y (pairs are symmetric about the x axis). Rotations are axial
    vectors, so a twist transforms with blockdiag(M, -M) for the reflection M = diag(1, -1, 1)."""
    M = np.diag([1.0, -1.0, 1.0])
    T6 = np.block([[M, np.zeros((3, 3))], [np.zeros((3, 3)), -M]])
    p = points[[2, 6]]                   # P2 (+,-,-) and P6 (+,-,+) mirror onto P3 and P7
    q = points[[3, 7]]
    W = np.array([12.0, 5.0, -4.0, 0, 0, 0])
    a = evaluate(case, p, W, joints=joints)
    b = evaluate(case, q, T6 @ W, joints=joints)
    assert np.abs(b.K - T6 @ a.K @ T6).max() < 1e-9 * np.abs(a.K).max()   # round-off of trig + inverses
    assert np.abs(b.twist - a.twist @ T6).max() < 1e-9 * np.abs(a.twist).max()
