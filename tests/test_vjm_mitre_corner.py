"""Mitred tube corners of the beam world: ASME B31.3's single-mitre flexibility as a corner compliance."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import femcheck
from femcheck.vjm.beam_world import Tube, _layout, tcp_deflections
from femcheck.vjm.bearing_world import cobot7_bearings_world, with_nominal_drives
from femcheck.vjm.dh import forward_kinematics
from femcheck.vjm.mitre_corner import (bend_bending_integral, corner_compliance, mitre_flexibility,
                                       mitre_flexibility_factor)

ROOT = Path(__file__).resolve().parents[1]


def test_flexibility_factor_law_reproduces_a_published_worked_value():
    """k = 1.52 / h^(5/6): a published B31.3 Table D300 worksheet (closely spaced mitre, same k(h) law) gives
    h = 0.097 -> k = 10.64; 0.3 % (its h is rounded to 2 digits: 0.0965-0.0975 spans 10.6 +- 0.05). A 1.65/h
    (the elbow law) would give 17.0."""
    assert mitre_flexibility_factor(0.097) == pytest.approx(10.64, rel=3e-3)
    assert mitre_flexibility_factor(5.0) == 1.0                    # the table's floor: k not less than unity


@pytest.mark.parametrize("D, T", [(0.140, 0.006), (0.120, 0.005), (0.100, 0.004)])
def test_single_right_angle_mitre_has_h_T_over_r2_and_bend_radius_r2(D, T):
    """theta = 45 deg, cot = 1: h = T (1 + 1) / (2 r2) = T / r2, R1 = r2, arc = pi r2 / 2 (exact, 1e-12);
    the world's tubes are D/T 20-25, inside the table's D/T <= 100."""
    m = mitre_flexibility(D, T, math.pi / 2)
    r2 = (D - T) / 2
    assert m.h == pytest.approx(T / r2, rel=1e-12) and m.R1_m == pytest.approx(r2, rel=1e-12)
    assert m.arc_m == pytest.approx(math.pi * r2 / 2, rel=1e-12)
    assert 10.0 < m.k < 13.0                                       # 11.3 (140x6) - 12.0 (100x4)


def test_out_of_range_corners_are_refused():
    with pytest.raises(ValueError, match="mitre angle 2 deg"):
        mitre_flexibility(0.1, 0.004, math.radians(2.0))
    with pytest.raises(ValueError, match="D / T <= 100"):
        mitre_flexibility(0.5, 0.004, math.pi / 2)


@pytest.mark.parametrize("angle_deg", [30.0, 90.0, 135.0])
def test_bend_integral_is_the_quadrature_of_the_bending_projection(angle_deg):
    """The closed form of int_0^alpha (I - t t^T) dphi equals a 2001-point Simpson quadrature along the arc
    (1e-10: Simpson's error ~ h^4); at 90 deg its eigenvalues are pi/4 - 1/2, pi/4 + 1/2 (in the plane) and
    pi/2 (about the plane's normal), exactly."""
    rng = np.random.default_rng(1)
    t_in = rng.standard_normal(3)
    t_in /= np.linalg.norm(t_in)
    e2 = np.cross(t_in, rng.standard_normal(3))
    e2 /= np.linalg.norm(e2)
    a = math.radians(angle_deg)
    P, alpha = bend_bending_integral(t_in, math.cos(a) * t_in + math.sin(a) * e2)
    assert alpha == pytest.approx(a, rel=1e-12)
    phi = np.linspace(0.0, a, 2001)
    t = np.cos(phi)[:, None] * t_in + np.sin(phi)[:, None] * e2
    f = np.eye(3)[None] - np.einsum("pi,pj->pij", t, t)
    w = np.ones(len(phi))
    w[1:-1:2], w[2:-1:2] = 4.0, 2.0
    np.testing.assert_allclose(P, np.einsum("p,pij->ij", w, f) * (phi[1] - phi[0]) / 3, rtol=0, atol=1e-10)
    if angle_deg == 90.0:
        np.testing.assert_allclose(np.linalg.eigvalsh(P), [math.pi / 4 - 0.5, math.pi / 4 + 0.5, math.pi / 2], atol=1e-12)


def test_corner_compliance_is_k_minus_one_times_the_arc_bending_compliance():
    """Right-angle corner of a 140 x 6 tube: about the bend plane's normal the excess compliance is
    (k - 1) R1 (pi/2) / (E I) (exact, 1e-12); it scales as 1 / E."""
    tube = Tube(0.140, 0.006)
    x, y = np.eye(3)[0], np.eye(3)[1]
    C = corner_compliance(tube, x, y)
    m = mitre_flexibility(0.140, 0.006, math.pi / 2)
    EI = tube.E_Pa * tube.section.Ix
    assert np.eye(3)[2] @ C @ np.eye(3)[2] == pytest.approx((m.k - 1) * m.R1_m * math.pi / 2 / EI, rel=1e-12)
    np.testing.assert_allclose(corner_compliance(dataclasses.replace(tube, E_Pa=35e9), x, y), 2 * C, rtol=1e-12)


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case(ROOT / "cases" / "cobot7.toml")


@pytest.mark.parametrize("corners", ["b31.3", "solid"])
def test_world_adds_each_corner_compliance_in_series_under_a_pure_moment(case, corners):
    """A pure moment M at the TCP loads every section of the clamped serial arm by the same M, so the TCP
    twist of the mitred world minus the rigid-corner world is, over the six corners (bodies 1-6; series
    compliances, linear drives), rotation sum_i D_i,tt M and translation sum_i (D_i,ut M + D_i,tt M x (x_tcp -
    x_i)) (1e-9 of the difference: the solves' round-off). Checks the corners' assembly (eigen-directions,
    springs, base frame, place) independently of the solver."""
    w = with_nominal_drives(cobot7_bearings_world(case, corners=corners))
    rigid = dataclasses.replace(w, corners="rigid")
    q = np.radians(np.array(case.identification.configurations_deg[:3], dtype=float))
    M = np.array([[0.0, 0.0, 0.0, 7.0, -4.0, 5.0]])
    d = tcp_deflections(w, q, M).twist[:, 0] - tcp_deflections(rigid, q, M).twist[:, 0]
    fk = forward_kinematics(w.chain, q)
    for i in range(len(q)):
        lay = _layout(w, fk, i)
        assert len(lay.corners) == 6 and not _layout(rigid, fk, i).corners
        ref = np.zeros(6)
        for node, (_, C) in lay.corners.items():
            turn = C[3:, 3:] @ M[0, 3:]
            ref += np.r_[C[:3, 3:] @ M[0, 3:] + np.cross(turn, lay.nodes[lay.tcp] - lay.nodes[node]), turn]
        np.testing.assert_allclose(d[i], ref, rtol=0, atol=1e-9 * np.abs(ref).max())
    # the corners add 19 % (B31.3) of the rigid-corner rotation here (the drives dominate a pure moment)
    assert np.abs(d[:, 3:]).max() > 0.1 * np.abs(tcp_deflections(rigid, q, M).twist[:, 0, 3:]).max()
