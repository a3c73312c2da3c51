"""Element compliances against closed forms (Timoshenko beam theory, Johnson's Hertz contact) and
the reference element values of docs/conventions.md / haptic_6psu.toml."""
from __future__ import annotations

import numpy as np
import pytest

from femcheck.compliance import (actuation_compliance, cable_stiffness, cantilever_compliance, effective_modulus,
                                 effective_radius, hertz_force, hertz_tangent_stiffness, line_contact_stiffness,
                                 motor_stiffness_at_cable, pin_bending_stiffness, rectangle_section, tube_section,
                                 universal_joint_compliance)
from femcheck.kinematics.frames import twist_shift

E, G = 69e9, 69e9 / 2.66


def test_cantilever_tip_deflection_is_PL3_over_3EI():
    sec = rectangle_section(0.014, 0.010)
    L = 0.2
    S = cantilever_compliance(L, E, G, sec)
    # closed forms (Euler-Bernoulli): exact to round-off
    assert S[0, 0] == pytest.approx(L**3 / (3 * E * 0.010 * 0.014**3 / 12), rel=1e-14)
    assert S[1, 1] == pytest.approx(L**3 / (3 * E * 0.014 * 0.010**3 / 12), rel=1e-14)
    assert S[2, 2] == pytest.approx(L / (E * 0.014 * 0.010), rel=1e-14)


def test_cantilever_compliance_inverts_the_12_6_4_tip_stiffness():
    sec = tube_section(0.006, 0.005)
    L = 0.18
    S = cantilever_compliance(L, E, G, sec)
    EI = E * sec.Ix
    K = np.zeros((6, 6))
    K[0, 0] = K[1, 1] = 12 * EI / L**3
    K[0, 4] = K[4, 0] = -6 * EI / L**2
    K[1, 3] = K[3, 1] = 6 * EI / L**2
    K[3, 3] = K[4, 4] = 4 * EI / L
    K[2, 2] = E * sec.A / L
    K[5, 5] = G * sec.Jt / L
    # inverse of a well-scaled 6x6: round-off only
    assert np.abs(S @ K - np.eye(6)).max() < 1e-10


def test_two_cantilevers_in_series_are_one_longer_cantilever():
    """Series elements add compliances once carried to a common point: S(a+b) = T S(a) T^T + S(b)."""
    sec = rectangle_section(0.014, 0.010)
    a, b = 0.12, 0.07
    T = twist_shift(np.array([0, 0, b]))   # tip of a -> tip of a+b
    S = T @ cantilever_compliance(a, E, G, sec) @ T.T + cantilever_compliance(b, E, G, sec)
    assert np.abs(S - cantilever_compliance(a + b, E, G, sec)).max() < 1e-12 * np.abs(S).max()


def test_timoshenko_shear_adds_L_over_kappa_G_A():
    sec = rectangle_section(0.014, 0.010)
    L = 0.05
    d = cantilever_compliance(L, E, G, sec, shear=True) - cantilever_compliance(L, E, G, sec)
    assert d[0, 0] == pytest.approx(L / (5 / 6 * G * sec.A), rel=1e-14)
    assert d[1, 1] == pytest.approx(d[0, 0], rel=1e-14)
    assert np.count_nonzero(d) == 2


def test_rectangle_torsion_constant_limits():
    # square: series solution Jt = 0.1406 a^4; Roark's closed approximation is within 0.2 % of it
    sec = rectangle_section(0.01, 0.01)
    assert sec.Jt / 0.01**4 == pytest.approx(0.1406, rel=3e-3)
    # thin strip (a/c = 20): Jt -> a c^3 / 3 (1 - 0.63 c/a), the same formula's asymptote to 1e-6
    thin = rectangle_section(0.02, 0.001)
    assert thin.Jt == pytest.approx(0.02 * 0.001**3 / 3 * (1 - 0.63 * 0.05), rel=1e-6)


def test_hertz_point_contact_against_hand_computation():
    # steel ball R = 3.5 mm on a flat UHMWPE seat, F = 15 N, by hand:
    # 1/E* = (1-0.3^2)/210e9 + (1-0.46^2)/0.8e9 = 4.3333e-12 + 9.855e-10 = 9.8983e-10 -> E* = 1.01027e9 Pa
    # k = (6 E*^2 R F)^(1/3) = (6 * 1.02065e18 * 3.5e-3 * 15)^(1/3) = (3.21505e17)^(1/3) = 6.8505e5 N/m
    Es = effective_modulus(210e9, 0.30, 0.8e9, 0.46)
    assert Es == pytest.approx(1.01027e9, rel=1e-4)
    k = hertz_tangent_stiffness(15.0, Es, effective_radius(3.5e-3))
    assert k == pytest.approx(6.8505e5, rel=2e-4)   # hand computation carried to 5 digits


def test_hertz_stiffness_is_the_derivative_of_the_force_law():
    Es, R = 1.0e9, 3.5e-3
    delta = 2e-5
    F = hertz_force(delta, Es, R)
    h = 1e-10
    dFdd = (hertz_force(delta + h, Es, R) - hertz_force(delta - h, Es, R)) / (2 * h)
    # central difference on a smooth power law: ~1e-8 relative
    assert hertz_tangent_stiffness(F, Es, R) == pytest.approx(dFdd, rel=1e-6)
    # seed 000 notation: E' = 2E*, R' = R*/2, stiffness E' (2 R' delta)^(1/2) is the same number
    assert 2 * Es * np.sqrt(2 * (R / 2) * delta) == pytest.approx(dFdd, rel=1e-6)


def test_concave_seat_stiffens_the_contact():
    Es = 1e9
    flat = hertz_tangent_stiffness(10.0, Es, effective_radius(3.5e-3, 0.0))
    socket = hertz_tangent_stiffness(10.0, Es, effective_radius(3.5e-3, -1 / 3.6e-3))
    assert socket > 3 * flat   # conformal contact: R* = 1/(1/3.5 - 1/3.6) mm = 126 mm vs 3.5 mm -> x3.3


def test_reference_element_values():
    # haptic_6psu.toml reference comments, quoted to 4 significant digits
    assert cable_stiffness(90e9, 1e-3, 0.9) == pytest.approx(7.854e4, rel=1e-3)
    assert motor_stiffness_at_cable(80e9, 0.004, 0.025, 0.010) == pytest.approx(8.042e5, rel=1e-3)
    Es_uj = effective_modulus(210e9, 0.30, 69e9, 0.33)
    assert line_contact_stiffness(0.006, Es_uj) == pytest.approx(5.464e8, rel=1e-3)
    assert pin_bending_stiffness(210e9, 1e-3, 0.024) == pytest.approx(5.727e5, rel=1e-3)


def test_joint_and_actuation_compliances_are_translational():
    S = universal_joint_compliance(2.0e8, 5.0e5)
    assert S[2, 2] == pytest.approx(1 / 2e8 + 1 / 5e5) and S[0, 0] == S[1, 1] == pytest.approx(1 / 2e8)
    assert not S[3:].any() and not S[:, 3:].any()
    e = np.array([0, 0, 1.0])
    A = actuation_compliance(1e-5, e)
    assert A[2, 2] == pytest.approx(1e-5) and np.count_nonzero(A) == 1
