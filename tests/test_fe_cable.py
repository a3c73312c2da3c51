"""Pretensioned cable element (femcheck/fe/cable.py) against the closed forms of a string, plus invariants."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from femcheck.fe.cable import assemble_cable_stiffness, cable_stiffness, cable_tensions, strand_geometry

EA, T, L = 7.0e4, 50.0, 0.9        # N, N, m: the reference case's 1 mm rope and a 50 N pretension


def _string(n_elements: int, EA=EA, T=T, L=L, axis=(0.0, 0.0, 1.0)):
    """A straight string of n elements along ``axis``, both ends held: (nodes, elements, K)."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    nodes = np.linspace(0.0, L, n_elements + 1)[:, None] * axis
    elements = np.c_[np.arange(n_elements), np.arange(1, n_elements + 1)]
    return nodes, elements, assemble_cable_stiffness(nodes, elements, EA, T).tocsc()


def _solve_held_ends(K, n_nodes, load_node, force):
    free = np.arange(3, 3 * (n_nodes - 1))                 # translations of the interior nodes
    f = np.zeros(3 * n_nodes)
    f[3 * load_node:3 * load_node + 3] = force
    u = np.zeros(3 * n_nodes)
    u[free] = spla.spsolve(K[free][:, free], f[free])
    return u


def test_midpoint_load_on_a_pretensioned_string_gives_PL_over_4T():
    """Transverse midpoint load P on a string of tension T held at both ends: δ = P L / (4 T) (small deflection,
    EA ≫ T; each half is a transverse spring T / (L/2)). The linearized element is exact for this (no
    discretization: any even number of elements), so the tolerance is round-off."""
    P = 1.0
    for n in (2, 4, 10):
        nodes, elements, K = _string(n)
        u = _solve_held_ends(K, n + 1, n // 2, [P, 0.0, 0.0])
        assert u[3 * (n // 2)] == pytest.approx(P * L / (4 * T), rel=1e-12)


def test_axial_load_gives_EA_over_L_and_quarter_point_splits_by_stiffness():
    """Axial: a string held at both ends, loaded along its axis at a node at a from one end: the two parts act in
    parallel, k = EA / a + EA / (L - a) (the closed loop's two strands); midpoint: 4 EA / L."""
    n = 4
    nodes, elements, K = _string(n)
    for node in (1, 2):
        a = L * node / n
        u = _solve_held_ends(K, n + 1, node, [0.0, 0.0, 1.0])
        assert 1.0 / u[3 * node + 2] == pytest.approx(EA / a + EA / (L - a), rel=1e-12)
    # one element, one end held: EA / L along the axis, T / L across it
    e, Ls = strand_geometry(nodes[[0, -1]], [[0, 1]])
    k = cable_stiffness(e, Ls, EA, T)[0][3:, 3:]
    assert k[2, 2] == pytest.approx(EA / L, rel=1e-14) and k[0, 0] == pytest.approx(T / L, rel=1e-14)


def test_symmetric_psd_and_rigid_translations_give_zero_force():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(2, 3))
    e, Ls = strand_geometry(x, [[0, 1]])
    K = cable_stiffness(e, Ls, EA, T)[0]
    assert np.allclose(K, K.T, rtol=0, atol=1e-12 * np.abs(K).max())
    assert np.linalg.eigvalsh(K).min() > -1e-9 * np.abs(K).max()           # round-off of a PSD matrix
    for d in np.eye(3):
        assert np.abs(K @ np.r_[d, d]).max() < 1e-10 * np.abs(K).max()
    # any displacement: the end forces balance (the element carries no net force)
    f = K @ rng.normal(size=6)
    assert np.abs(f[:3] + f[3:]).max() < 1e-10 * np.abs(f).max()


def test_rigid_rotation_is_free_without_tension_and_costs_T_L_theta2_with_it():
    """Linearized rigid rotation u = θ × x: zero force when T = 0; with T > 0 the energy uᵀ K u = T L θ²
    (the chord's second-order stretch L θ² / 2 times T, twice: the geometric stiffness, module docstring)."""
    x = np.array([[0.1, 0.2, 0.0], [0.1, 0.2, L]])
    theta = np.array([1e-3, 0.0, 0.0])
    u = np.r_[np.cross(theta, x[0]), np.cross(theta, x[1])]
    e, Ls = strand_geometry(x, [[0, 1]])
    assert np.abs(cable_stiffness(e, Ls, EA, 0.0)[0] @ u).max() < 1e-12
    K = cable_stiffness(e, Ls, EA, T)[0]
    assert u @ K @ u == pytest.approx(T * L * theta[0] ** 2, rel=1e-12)


def test_tensions_follow_the_axial_stretch():
    x = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, L]])
    e, Ls = strand_geometry(x, [[0, 1]])
    assert cable_tensions(e, Ls, EA, T, [[0, 0, 0]], [[1e-4, 0, 1e-4]])[0] == pytest.approx(T + EA / L * 1e-4)


def test_zero_length_strand_is_refused():
    with pytest.raises(ValueError, match="zero length"):
        strand_geometry(np.zeros((2, 3)), [[0, 1]])
