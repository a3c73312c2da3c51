"""Unit tests of the contact building blocks: projection, pairing operators, friction law, half-space
closed forms and the low-rank-updated factorization of the modified Newton iteration."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from femcheck.compliance.hertz_point_contact import effective_modulus, hertz_force
from femcheck.errors import ConvergenceError
from femcheck.fe.contact import status as st
from femcheck.fe.contact.coulomb_friction import return_mapping
from femcheck.fe.contact.half_space import boussinesq, hertz_axis_displacement, hertz_line, hertz_point
from femcheck.fe.contact.pairing import _closest_on_triangles

E, NU = 210e9, 0.3


def test_closest_point_matches_dense_sampling():
    rng = np.random.default_rng(1)
    k = 200
    A, B, C = rng.normal(size=(3, k, 3))
    x = rng.normal(size=(k, 3)) * 2.0
    cp, dist = _closest_on_triangles(x, A, B, C)
    # dense barycentric sampling of each triangle (step 1/300)
    u, v = np.meshgrid(np.linspace(0, 1, 301), np.linspace(0, 1, 301))
    keep = (u + v) <= 1.0
    u, v = u[keep], v[keep]
    samples = A[:, None] + u[None, :, None] * (B - A)[:, None] + v[None, :, None] * (C - A)[:, None]
    brute = np.linalg.norm(samples - x[:, None], axis=2).min(axis=1)
    # the exact distance is never above the sampled one, and below it by at most the sampling step
    # times the triangle size (~1/300 · 3)
    assert np.all(dist <= brute + 1e-12)
    assert np.all(brute - dist < 0.02)


def test_pairing_operators_reproduce_rigid_motions():
    from femcheck.fe.checks import contact_patch

    problem, pair, basis = contact_patch.build("coarse")
    mesh_upper = basis.element_dofs[:, basis.mesh.t.shape[1] // 9:]  # upper block = the refined 8/9 of tets
    upper = np.zeros(basis.N, dtype=bool)
    upper[np.unique(mesh_upper)] = True
    comp = np.arange(basis.N) % 3
    for c, value in ((2, 1e-6), (0, 2e-6)):
        u = np.where(upper & (comp == c), value, 0.0)
        gap = pair.B_n @ u
        slip = (pair.B_t @ u).reshape(-1, 2)
        e = np.eye(3)[c]
        # the operators are exact for rigid translations (shape functions sum to one): 1e-12 relative
        assert np.allclose(gap, pair.normal @ e * value, rtol=0, atol=1e-12 * value)
        assert np.allclose(slip, np.c_[pair.t1 @ e, pair.t2 @ e] * value, rtol=0, atol=1e-12 * value)
    # the integration weights sum to the interface area L² (exact quadrature of a plane, round-off only)
    assert pair.weights.sum() == pytest.approx(contact_patch.L**2, rel=1e-12)
    assert np.allclose(pair.g0, 0.0, atol=1e-15)


def test_return_mapping_stick_slide_open():
    slip = np.array([[1e-10, 0.0], [1e-6, 0.0], [1e-6, 0.0], [0.0, 0.0]])
    zeros = np.zeros((4, 2))
    eps = np.full(4, 1e15)
    p = np.array([1e6, 1e6, 0.0, 1e6])
    t, status = return_mapping(slip, zeros, zeros, eps, 0.3, p)
    assert status.tolist() == [st.STICK, st.SLIDE, st.OPEN, st.STICK]
    assert t[0, 0] == pytest.approx(1e5)            # stick: ε s (exact arithmetic)
    assert np.linalg.norm(t[1]) == pytest.approx(0.3e6)  # slide: exactly μ p
    assert np.all(t[2] == 0.0)
    t0, s0 = return_mapping(slip, zeros, zeros, eps, 0.0, p)  # frictionless: closed points slide, t = 0
    assert s0.tolist() == [st.SLIDE, st.SLIDE, st.OPEN, st.SLIDE] and np.all(t0 == 0.0)


def test_hertz_closed_forms_are_consistent():
    E_star = float(effective_modulus(E, NU, E, NU))
    h = hertz_point(15.0, E_star, 5e-3)
    # F = 4/3 E* sqrt(R) δ^1.5 inverts a, δ (same closed form two ways: round-off only)
    assert float(hertz_force(h.delta, E_star, 5e-3)) == pytest.approx(15.0, rel=1e-12)
    # surface value of the axis integral equals π a p0 (1−ν²)/(2E), half the approach (quadrature 1e-9)
    v0 = float(hertz_axis_displacement(0.0, h.a, h.p0, E, NU))
    assert v0 == pytest.approx(np.pi * h.a * h.p0 * (1 - NU**2) / (2 * E), rel=1e-9)
    assert 2 * v0 == pytest.approx(h.delta, rel=1e-9)
    # far from the contact the Hertz field tends to Boussinesq's point load: difference O((a/d)²) ≈ 0.25 % at 20 a
    d = 20 * h.a
    vb = boussinesq(15.0, E, NU, 0.0, d)[1]
    assert float(hertz_axis_displacement(d, h.a, h.p0, E, NU)) == pytest.approx(float(vb), rel=1e-2)
    a, p0 = hertz_line(200e3, E_star, 5e-3)
    # line contact: P' = π a p0 / 2 (integral of the elliptical pressure, exact)
    assert np.pi * a * p0 / 2 == pytest.approx(200e3, rel=1e-12)


def test_lowrank_update_equals_direct_solve():
    from femcheck.fe.linear_solver import factorize
    from femcheck.fe.newton import _LowRankUpdated

    rng = np.random.default_rng(3)
    n, m = 60, 12
    Q = sp.random(n, n, density=0.1, random_state=4)
    K = sp.csr_matrix(Q @ Q.T + sp.identity(n) * 5.0)
    Bn = sp.csr_matrix(rng.normal(size=(m, n)))
    Bt = sp.csr_matrix(rng.normal(size=(2 * m, n)))
    wn, wt = rng.uniform(1, 2, m), rng.uniform(1, 2, m)
    s0 = np.array([st.OPEN, st.STICK, st.SLIDE] * 4, dtype=np.int8)
    s1 = np.array([st.STICK, st.SLIDE, st.OPEN] * 4, dtype=np.int8)

    def matrix(s):
        A = K + Bn.T @ sp.diags(wn * (s > 0)) @ Bn
        return sp.csr_matrix(A + Bt.T @ sp.diags(np.repeat(wt * (s == st.STICK), 2)) @ Bt)

    fac = _LowRankUpdated(factorize(matrix(s0), "splu"), s0, Bn, Bt, wn, wt, max_rank=100)
    assert fac.set_status(s1)
    b = rng.normal(size=n)
    x = fac.solve(b)
    # Sherman–Morrison–Woodbury is exact: agreement to round-off of a well-conditioned system
    assert np.allclose(matrix(s1) @ x, b, rtol=0, atol=1e-9 * np.linalg.norm(b))


def test_nonconvergence_raises_with_history_and_chattering_points():
    from femcheck.fe.checks import friction_block
    from femcheck.fe.newton import solve_contact

    problem, pair, basis = friction_block.build("coarse", "slide")
    with pytest.raises(ConvergenceError) as info:
        solve_contact(problem, 1, initial_closure=1e-12, max_iter=2)
    err = info.value
    assert len(err.residual_history) >= 2
    assert "chattering" in err.detail and "n_chattering" in err.detail
