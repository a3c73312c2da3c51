"""Newton on the contact energy for a condensed stiffness (femcheck.fe.contact.condensed_solver):
closed forms of a floating body in a clearance, the iteration-matrix spring, and the named failure."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from femcheck.errors import ConvergenceError
from femcheck.fe.contact.condensed_solver import solve_condensed_contact

K = 1e6  # N/m, each body's spring
C = 1e-5  # m, clearance (the cross floats in 2C, as a pin in its bore)
EPS_W = 1e12  # N/m, penalty x area: stiff against K, so the Uzawa updates are few


def _chain(F=10.0):
    """Link b (nodes b, b2: spring K) pushes the floating cross (c1, c2: spring K) across a clearance 2C
    onto the held yoke. u = (u_b, u_b2, u_c1, u_c2); gaps g1 = u_c1 − u_b2 (touching at the start),
    g2 = 2C − u_c2. Only the two bodies' own springs are in S: both bodies float (S is singular)."""
    k = np.array([[1.0, -1.0], [-1.0, 1.0]]) * K
    S = np.zeros((4, 4))
    S[:2, :2] += k
    S[2:, 2:] += k
    B = sp.csr_matrix(np.array([[0.0, -1.0, 1.0, 0.0], [0.0, 0.0, 0.0, -1.0]]))
    g0 = np.array([0.0, 2 * C])
    f = np.array([F, 0.0, 0.0, 0.0])
    return S, f, B, g0, np.full(2, EPS_W), np.ones(2)


@pytest.mark.parametrize("predicted", [None, np.array([True, True])])
def test_floating_body_seats_across_the_clearance(predicted):
    """Closed form: u_c2 = 2C, u_c1 = 2C + F/K, u_b = 2C + 2F/K, both contact forces F, at both load levels.

    Tolerance: the Uzawa loop stops at the requested penetration (1e-3 of the body compression F/K)."""
    S, f, B, g0, eps, w = _chain()
    tol = 1e-3 * 10.0 / K
    r = solve_condensed_contact(S, f, B, g0, eps, w, [0.25, 1.0], initial_closed=predicted, penetration_tol=tol)
    for lf, u, p in zip((0.25, 1.0), r.u, r.pressure):
        F = 10.0 * lf
        assert u == pytest.approx([2 * C + 2 * F / K, 2 * C + F / K, 2 * C + F / K, 2 * C], abs=2 * tol)
        assert p * w == pytest.approx([F, F], rel=1e-9)  # equilibrium is exact, the penetration is not
    assert r.closed[-1].all()
    # the spring of the iteration matrix (both bodies float before they seat) carries no force at the end
    assert r.residual_history[-1] <= 1e-9 * 10.0
    if predicted is None:
        assert r.stabilized_iterations > 0
    assert r.stabilization_force_share < 1e-6


def test_predicted_active_set_saves_iterations():
    S, f, B, g0, eps, w = _chain()
    a = solve_condensed_contact(S, f, B, g0, eps, w, [1.0], penetration_tol=1e-8)
    b = solve_condensed_contact(S, f, B, g0, eps, w, [1.0], initial_closed=np.array([True, True]), penetration_tol=1e-8)
    assert b.iterations <= a.iterations
    assert b.stabilized_iterations == 0  # the predicted set holds both bodies: no spring needed


def test_pulled_apart_is_a_named_error_not_numbers():
    """A load that pulls the link off the cross has no equilibrium: ConvergenceError with the history."""
    S, f, B, g0, eps, w = _chain(F=-10.0)
    with pytest.raises(ConvergenceError, match="unbounded|not converge") as exc:
        solve_condensed_contact(S, f, B, g0, eps, w, [1.0], initial_closed=np.array([True, True]), penetration_tol=1e-8)
    assert exc.value.residual_history


def test_iteration_limit_reports_chattering_points():
    """Out of iterations: ConvergenceError naming the points whose status changed, with the residual history."""
    S, f, B, g0, eps, w = _chain()
    with pytest.raises(ConvergenceError, match="did not converge") as exc:
        solve_condensed_contact(S, f, B, g0, eps, w, [1.0], penetration_tol=1e-8, max_iter=1,
                                initial_closed=np.array([False, True]), point_info=lambda i: [{"point": int(k)} for k in i])
    assert len(exc.value.residual_history) >= 1
    assert "chattering" in exc.value.detail and "n_chattering" in exc.value.detail


def test_woodbury_active_set_updates_match_refactorization():
    """A string of 61 nodes (springs 1e5 N/m) pressed by a uniform load onto a parabolic obstacle: the
    contact zone grows from the apex over many iterations. Solving the changed active sets by Woodbury updates of the
    last Cholesky must give the refactorized solution (round-off of the update, rel 1e-8) with fewer
    factorizations, and the contact forces carry the load (equilibrium is exact at convergence)."""
    n, k, F = 61, 1e5, 50.0
    S = np.zeros((n, n))
    for i in range(n - 1):
        S[np.ix_([i, i + 1], [i, i + 1])] += k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    x = np.linspace(-1.0, 1.0, n)
    g0 = 1e-3 * x**2
    B = sp.identity(n, format="csr")
    f = np.full(n, -F / n)
    eps, w = np.full(n, 1e9), np.ones(n)
    kw = dict(initial_closed=g0 <= 0.0, penetration_tol=1e-9)
    ref = solve_condensed_contact(S, f, B, g0, eps, w, [0.5, 1.0], low_rank_fraction=0.0, **kw)
    upd = solve_condensed_contact(S, f, B, g0, eps, w, [0.5, 1.0], low_rank_fraction=0.5, **kw)
    assert upd.low_rank_updates > 0 and upd.factorizations < ref.factorizations
    assert ref.low_rank_updates == 0
    assert np.allclose(upd.u, ref.u, rtol=0, atol=1e-8 * np.abs(ref.u).max())
    assert np.array_equal(upd.closed, ref.closed)
    assert float(np.sum(upd.pressure[-1] * w)) == pytest.approx(F, rel=1e-8)
