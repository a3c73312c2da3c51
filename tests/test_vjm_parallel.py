"""Parallel VJM (seed 001 eqs. 1-6) on the HISS case, and the weight fitting / fine-tuning (eqs. 10-12, sec. 3.3)."""
import numpy as np
import pytest

from femcheck.case import load_case
from femcheck.vjm.parallel_vjm import leg_compliance, leg_stiffness, parallel_stiffness
from femcheck.vjm.rcube_geometry import forward_position, leg_jacobians, leg_poses
from femcheck.vjm.weight_fitting import fine_tune, fit_weights, scaled_stiffness, with_norms


@pytest.fixture(scope="module")
def hiss():
    return load_case("cases/hiss.toml")


@pytest.fixture(scope="module")
def at_test_points(hiss):
    geom = hiss.rcube
    legs = leg_poses(geom, forward_position(geom, hiss.test_point_angles_rad))
    return legs, *leg_jacobians(legs)


def test_leg_chains_close_in_the_plane_of_their_passive_axes(hiss, at_test_points):
    legs, _, _ = at_test_points
    g = hiss.rcube
    E = np.eye(3)
    for i in range(3):
        # closure computed through the chain, not through eq. 1: the passive axes of leg i are parallel to e_i,
        # so the crank tip B, the knee C and the platform point P must share one plane normal to e_i
        np.testing.assert_allclose((legs.P - legs.B[i]) @ E[i], 0.0, atol=1e-14)   # round-off of metre sums
        np.testing.assert_allclose((legs.C[i] - legs.B[i]) @ E[i], 0.0, atol=1e-14)
        # the knee angle as the signed angle between the link vectors about the passive axis (atan2, not the
        # law of cosines the pose solver uses) equals the stored one
        u, v = legs.C[i] - legs.B[i], legs.P - legs.C[i]
        signed = np.arctan2(np.einsum("mk,mk->m", np.cross(u, v), legs.passive_axis[i]), np.einsum("mk,mk->m", u, v))
        np.testing.assert_allclose(signed, legs.knee_rad[i], atol=1e-12)  # atan2 vs arccos round-off
    # the legs close with the seed's link lengths (round-off only)
    np.testing.assert_allclose(np.linalg.norm(legs.B - legs.A, axis=-1), g.l1, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(legs.C - legs.B, axis=-1), g.l2, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(legs.P[None] - legs.C, axis=-1), g.l3, atol=1e-14)
    assert np.all(legs.knee_rad < 0)                 # seed 001 sec. 2.1: negative knee configuration


def test_leg_stiffness_invariants(hiss, at_test_points):
    _, Jt, Jp = at_test_points
    K_legs, K = parallel_stiffness(Jt, hiss.K_theta, Jp)
    for Ki, Jpi in zip(K_legs.reshape(-1, 6, 6), Jp.reshape(-1, 6, 3)):
        scale = np.abs(Ki).max()
        # symmetric up to the round-off of a 9x9 inverse of entries spanning 1e-9..1e-1 (cond ~ 1e9)
        np.testing.assert_allclose(Ki, Ki.T, atol=1e-9 * scale)
        ev = np.linalg.eigvalsh(Ki)
        assert ev.min() > -1e-9 * scale              # positive semi-definite, same round-off
        # rank = 6 - number of passive joints (3 parallel revolutes leave 3 twists free)
        assert int(np.sum(ev > 1e-9 * scale)) == 6 - Jpi.shape[1]
        # the passive twists cost no force: K_i J_phi = 0
        assert np.abs(Ki @ Jpi).max() < 1e-9 * scale * np.abs(Jpi).max()
    for Kp in K:                                     # three legs constrain all six directions
        assert np.linalg.eigvalsh(Kp).min() > 0


def test_bordered_inverse_equals_schur_complement(hiss, at_test_points):
    _, Jt, Jp = at_test_points
    J, P = Jt[0], Jp[0]
    C = leg_compliance(J, hiss.K_theta)
    Ci = np.linalg.inv(C)
    G = Ci @ P
    K_schur = Ci - G @ np.linalg.solve(np.swapaxes(P, -1, -2) @ G, np.swapaxes(G, -1, -2))
    K_bord = leg_stiffness(J, hiss.K_theta, P)
    # two algebraic routes to the same matrix; cond(C) ~ 1e9 leaves ~1e-7 relative
    np.testing.assert_allclose(K_bord, K_schur, atol=1e-6 * np.abs(K_schur).max())
    # without passive joints the leg is a serial chain: K = C^-1
    np.testing.assert_allclose(leg_stiffness(J, hiss.K_theta, np.zeros((J.shape[0], 6, 0))), Ci,
                               rtol=1e-6, atol=1e-6 * np.abs(Ci).max())


def test_isotropic_point_is_symmetric_under_leg_permutation(hiss):
    """TP2 and TP3 lie on the diagonal; the layout is invariant under the cyclic axis permutation x->y->z."""
    geom = hiss.rcube
    Jt, Jp = leg_jacobians(leg_poses(geom, forward_position(geom, np.deg2rad([[30.0, 30.0, 30.0]]))))
    _, K = parallel_stiffness(Jt, hiss.K_theta, Jp)
    Pi = np.zeros((3, 3))
    Pi[1, 0] = Pi[2, 1] = Pi[0, 2] = 1.0
    Q = np.kron(np.eye(2), Pi)
    # exact symmetry of the model; round-off of the inverses only
    np.testing.assert_allclose(Q @ K[0] @ Q.T, K[0], atol=1e-8 * np.abs(K[0]).max())


def _jac(geom, phi):
    return leg_jacobians(leg_poses(geom, forward_position(geom, phi)))


def _synthetic(hiss, at_test_points, w_true, n_per_point=5, seed=1):
    _, Jt, Jp = at_test_points
    rng = np.random.default_rng(seed)
    idx = np.repeat(np.arange(Jt.shape[1]), n_per_point)
    F = rng.normal(size=(idx.size, 6)) * [5, 5, 5, 0.3, 0.3, 0.3]     # D/F-like loads: < 10 N, < 0.5 N m
    wmap = hiss.fitting.weight_map

    def predict(w):
        _, K = parallel_stiffness(Jt, scaled_stiffness(hiss.K_theta, w, wmap), Jp)
        return np.linalg.solve(K[idx], F[..., None])[..., 0]

    return predict, predict(w_true)


def test_weight_fit_recovers_identifiable_weights_and_flags_the_others(hiss, at_test_points):
    w_true = np.array([0.88, 0.6, 0.94, 0.99, 0.87, 0.5, 0.98, 0.7, 0.55, 0.4, 0.8])
    predict, meas = _synthetic(hiss, at_test_points, w_true)
    fit = fit_weights(predict, meas, hiss.fitting.n_weights, restarts=10, seed=3)
    # W4 and W8 scale link 2's in-plane bending (its y translation and z rotation): the three parallel passive
    # joints absorb exactly these motions, so no platform load can identify them (structural, any data)
    flagged = set(np.flatnonzero(fit.unidentifiable))
    assert flagged == {3, 7}
    # round-off level sensitivity for those two; the others are seen (relative sensitivity 8e-3 .. 1 here)
    assert np.all(fit.sensitivity[[3, 7]] < 1e-6) and np.all(np.delete(fit.sensitivity, [3, 7]) > 1e-4)
    ok = [i for i in range(11) if i not in flagged]
    # noise-free data: the best start converges to the true weights (solver tolerance ~1e-8, cond of the fit)
    np.testing.assert_allclose(fit.weights[ok], w_true[ok], rtol=1e-4)
    assert fit.cost < 1e-20


def test_fine_tuning_recovers_a_linear_distortion():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(40, 6)) * 1e-3
    a, b = np.array([0.9, 1.1, 0.8, 1.3, 0.7, 1.0]), np.array([1e-4, -2e-4, 0, 3e-4, 0, -1e-4])
    ft = fine_tune(with_norms(x)[:, :6], a * x + b)
    # exact linear data: least-squares line recovers it up to round-off
    np.testing.assert_allclose(ft.a, a, rtol=1e-9)
    np.testing.assert_allclose(ft.b, b, atol=1e-12)
    assert np.all(ft.rms_after < 1e-12) and np.all(ft.rms_before[ft.a != 1.0] > 1e-5)
    # with noise the correction can only lower the RMS error (it is the least-squares line)
    y = a * x + b + rng.normal(size=x.shape) * 1e-4
    ft = fine_tune(x, y)
    assert np.all(ft.rms_after <= ft.rms_before + 1e-18)


# seed 001 Table 2, D/F fit, W1..W11
TABLE2_DF = np.array([0.884, 0.038, 0.941, 0.991, 0.866, 0.258, 0.977, 0.978, 0.054, 0.020, 0.125])


def _deflection_mm_under_1kg_negative_diagonal(hiss):
    from femcheck.vjm.rcube_geometry import rcube_stiffness
    K = scaled_stiffness(hiss.K_theta, TABLE2_DF, hiss.fitting.weight_map, "quadratic")   # eq. 10 as printed
    P = forward_position(hiss.rcube, hiss.test_point_angles_rad)
    _, Kp = rcube_stiffness(hiss.rcube, K, P)
    F = np.array([-1.0, -1.0, -1.0, 0, 0, 0]) / np.sqrt(3) * 9.81    # 1 kg along the negative diagonal (sec. 4)
    d = np.linalg.solve(Kp, np.broadcast_to(F, (len(P), 6))[..., None])[..., 0]
    return 1e3 * np.linalg.norm(d[:, :3], axis=1)


def test_table2_df_weights_make_tp3_the_most_compliant_point(hiss):
    d = _deflection_mm_under_1kg_negative_diagonal(hiss)
    # seed 001 sec. 5: TP3 is the most compliant test point. It holds for the D/F column under the quadratic
    # reading only (exact argmax; margin 25.71 vs 25.62 mm); under the linear reading TP1 is (1.15 vs 0.81 mm)
    assert int(np.argmax(d)) == 2


@pytest.mark.xfail(strict=True, reason=(
    "cannot be met by any planar two-link leg of the seed's link lengths: in leg i's plane the knee angle is fixed "
    "by the distance rho from the crank tip B to the platform point P alone (cos q = (rho^2 - l2^2 - l3^2) / "
    "(2 l2 l3)), and over TP1-TP13 P moves over the corners and edges of a square of side l1 = 122.3 mm "
    "(l1 sin(phi) for phi = +-30 deg) offset by the crank (l1 cos(phi_i) - c, h). Over every crank-axis "
    "placement (c, h) the distances from B to those points make the knee span at least 114.8 deg; the seed's "
    "-147 ... -38 deg is 109 deg (test_knee_span_cannot_shrink_to_the_seeds_109_deg). The case's placement gives -152 ... -21 deg; the best placement misses the "
    "seed's band +-5 deg by 1.53 deg at both ends (test_no_crank_axis_placement_gives_the_seed_knee_range)"))
def test_knee_angles_lie_in_the_seed_range(hiss, at_test_points):
    legs, _, _ = at_test_points
    k = np.rad2deg(legs.knee_rad)
    # seed 001 sec. 2.1 reports -147 ... -38 deg over the TPs; 5 deg = reading the range off the paper
    assert k.min() >= -147 - 5 and k.max() <= -38 + 5


@pytest.mark.xfail(strict=True, reason=(
    "cannot be met under eq. 10 read as printed (quadratic, K' = W K W^T): the Table 2 D/F weights deflect the "
    "assumed layout 11-26 mm under 1 kg while the seed measured at most about 6 mm, and no crank-axis placement "
    "(c, h) gets below 14.1 mm (test_no_crank_axis_placement_gives_the_measured_deflection_order); the three "
    "Table 2 columns then disagree by a factor 22. Under the linear reading, the case's default, the largest is "
    "1.15 mm and the check passes (tests/test_vjm_hiss_consistency.py)"))
def test_deflection_with_paper_weights_has_the_measured_order(hiss):
    # seed 001 sec. 4: measured deflections are a few mm; 10 mm allows the order, not the value
    assert _deflection_mm_under_1kg_negative_diagonal(hiss).max() <= 10.0


def test_no_crank_axis_placement_gives_the_seed_knee_range(hiss):
    """Layout inference. Eq. 1 fixes the crank direction at phi = 0 and the passive axes, but
    not where the crank axis sits: A = S e_i + (S + c) e_j + (S - h) e_k keeps r_i = S + l1 sin(phi_i1) for any
    c, h (the case has c = l1, h = 130 mm). The knee follows in closed form from the distance B -> P in the leg
    plane. Over a 1 mm grid of (c, h), refined by Nelder-Mead, no placement puts the 39 knees over TP1-TP13
    within -147 ... -38 deg +- 5 deg: the best (c = 114.1 mm, h = +-128.5 mm: -153.5 ... -31.5 deg) misses the
    band by 1.53 deg at both ends. The knee span over the TPs cannot shrink below 114.8 deg (next test); the
    seed's span is 109 deg."""
    g = hiss.rcube
    phi = hiss.test_point_angles_rad
    c = np.arange(-0.10, 0.35, 0.001)[:, None, None]
    h = np.arange(-0.30, 0.30, 0.001)[None, :, None]
    reach, lo, hi = _knee_range(g, phi, c, h)
    miss = np.where(reach, np.maximum(-152.0 - lo, hi + 33.0), np.inf)
    assert reach.sum() > 1000                                 # the search covers many reachable placements
    assert miss.min() > 1.5                                   # 1.94 deg on this grid
    from scipy.optimize import minimize

    def miss_at(x):
        r, lo_, hi_ = _knee_range(g, phi, np.array(x[0]), np.array(x[1]))
        return float(max(-152.0 - lo_, hi_ + 33.0)) if r else 1e3

    i, j = np.unravel_index(np.argmin(miss), miss.shape)
    best = minimize(miss_at, [c.ravel()[i], h.ravel()[j]], method="Nelder-Mead", options={"xatol": 1e-7, "fatol": 1e-9})
    assert best.fun == pytest.approx(1.53, abs=0.01)          # minimax: both ends 1.53 deg outside the band
    # the closed form, at the case's own placement, reproduces the layout module's knees
    legs = leg_poses(g, forward_position(g, phi))
    reach0, lo0, hi0 = _knee_range(g, phi, np.array(g.l1), np.array(g.knee_plane_offset_m))
    assert reach0 and lo0 == pytest.approx(np.degrees(legs.knee_rad).min(), abs=1e-9)
    assert hi0 == pytest.approx(np.degrees(legs.knee_rad).max(), abs=1e-9)


def test_knee_span_cannot_shrink_to_the_seeds_109_deg(hiss):
    """The geometric argument of the knee-range xfail, as a number: over a 2 mm grid of crank-axis placements
    (c, h) that reach every TP, refined by Nelder-Mead, the smallest knee span max(q) - min(q) over the 39 knees
    is 114.8 deg (c = 114.1 mm, h = -115.6 mm); the seed reports 109 deg. 0.1 deg: the optimizer's tolerance."""
    from scipy.optimize import minimize
    g, phi = hiss.rcube, hiss.test_point_angles_rad
    c = np.arange(-0.10, 0.35, 0.002)[:, None, None]
    h = np.arange(-0.30, 0.30, 0.002)[None, :, None]
    reach, lo, hi = _knee_range(g, phi, c, h)
    span = np.where(reach, hi - lo, np.inf)
    i, j = np.unravel_index(np.argmin(span), span.shape)

    def span_at(x):
        r, lo_, hi_ = _knee_range(g, phi, np.array(x[0]), np.array(x[1]))
        return float(hi_ - lo_) if r else 1e3

    best = minimize(span_at, [c.ravel()[i], h.ravel()[j]], method="Nelder-Mead", options={"xatol": 1e-8, "fatol": 1e-10})
    assert best.fun == pytest.approx(114.83, abs=0.1) and best.fun > 109.0 + 5.0


def _knee_range(g, phi, c, h):
    """(all TPs reachable, min knee, max knee) in deg for crank-axis placements c, h (broadcast, TPs last)."""
    reach, lo, hi = True, np.inf, -np.inf
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        dj = g.l1 * np.sin(phi[:, j]) - c + g.l1 * np.cos(phi[:, i])
        dk = h + g.l1 * np.sin(phi[:, k])
        cq = (dj ** 2 + dk ** 2 - g.l2 ** 2 - g.l3 ** 2) / (2 * g.l2 * g.l3)
        q = -np.degrees(np.arccos(np.clip(cq, -1, 1)))
        reach = reach & np.all(np.abs(cq) <= 1, axis=-1)      # every TP within reach of the 2R chain
        lo, hi = np.minimum(lo, q.min(axis=-1)), np.maximum(hi, q.max(axis=-1))
    return reach, lo, hi


def _max_deflection_mm(hiss, weights, c, h):
    import dataclasses

    from femcheck.errors import UnreachablePoseError
    from femcheck.vjm.rcube_geometry import rcube_stiffness
    g = dataclasses.replace(hiss.rcube, crank_axis_offset_m=float(c), knee_plane_offset_m=float(h))
    K = scaled_stiffness(hiss.K_theta, weights, hiss.fitting.weight_map, "quadratic")      # eq. 10 as printed
    try:
        P = forward_position(g, hiss.test_point_angles_rad)
        _, Kp = rcube_stiffness(g, K, P)
    except UnreachablePoseError:
        return np.inf, -1
    F = np.array([-1.0, -1.0, -1.0, 0, 0, 0]) / np.sqrt(3) * 9.81
    d = 1e3 * np.linalg.norm(np.linalg.solve(Kp, np.broadcast_to(F, (len(P), 6))[..., None])[..., 0][:, :3], axis=1)
    return float(d.max()), int(np.argmax(d))


def test_no_crank_axis_placement_gives_the_measured_deflection_order(hiss):
    """Layout inference for the <= 10 mm test: over a 5 mm grid of crank-axis placements (c, h) (183 reach every
    TP), refined by Nelder-Mead, the largest deflection under 1 kg along the negative diagonal with the Table 2
    D/F weights and eq. 10 as printed (K' = W K W) is at least 14.1 mm (c = -16.7 mm, h = 0)."""
    from scipy.optimize import minimize
    grid = [(_max_deflection_mm(hiss, TABLE2_DF, c, h)[0], c, h)
            for c in np.arange(-0.10, 0.35, 0.005) for h in np.arange(-0.30, 0.30, 0.005)]
    grid = sorted(g for g in grid if np.isfinite(g[0]))
    assert len(grid) > 150
    best = min((minimize(lambda x: _max_deflection_mm(hiss, TABLE2_DF, *x)[0], [c, h], method="Nelder-Mead",
                         options={"xatol": 1e-6, "fatol": 1e-6}) for _, c, h in grid[:3]), key=lambda r: r.fun)
    assert best.fun == pytest.approx(14.12, abs=0.05) and best.fun > 10.0
    # the case's own placement is one of them: the module default c = l1 reproduces the xfail's 25.7 mm
    assert _max_deflection_mm(hiss, TABLE2_DF, hiss.rcube.l1, hiss.rcube.knee_plane_offset_m)[0] == pytest.approx(
        _deflection_mm_under_1kg_negative_diagonal(hiss).max(), rel=1e-12)


def test_crank_axis_offset_is_a_case_key_and_keeps_eq1(hiss):
    import tomllib
    from pathlib import Path

    from femcheck.case import build_case
    raw = tomllib.loads(Path("cases/hiss.toml").read_text())
    raw["geometry"]["crank_axis_offset_m"] = 0.11410745
    raw["geometry"]["knee_plane_offset_m"] = 0.12846929
    moved = build_case(raw, "x.toml")
    g = moved.rcube
    assert g.c == 0.11410745 and hiss.rcube.c == hiss.rcube.l1          # absent key: the module's layout, c = l1
    legs = leg_poses(g, forward_position(g, hiss.test_point_angles_rad))
    # eq. 1 still holds through the chain (P and B share the plane normal to the passive axis of each leg)
    for i in range(3):
        np.testing.assert_allclose(legs.P[:, i], legs.B[i][:, i], atol=1e-14)
    # the knees of the best placement of the knee-range search (closed form there, chain here)
    k = np.degrees(legs.knee_rad)
    assert k.min() == pytest.approx(-153.53, abs=0.01) and k.max() == pytest.approx(-31.47, abs=0.01)
