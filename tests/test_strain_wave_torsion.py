"""The strain-wave gear's piecewise-linear torsion law (Harmonic Drive catalogue K1, K2, K3 over 0..T1, T1..T2, >T2)."""
from __future__ import annotations

import numpy as np
import pytest

from femcheck.vjm.strain_wave_torsion import StrainWaveTorsion

#: size 32, ratio > 50, as the CHA / CSD engineering data list it (T1, T2 N m; K1, K2, K3 N m/rad)
SIZE32 = StrainWaveTorsion((29.0, 108.0), (67e3, 110e3, 120e3))


def test_catalogue_worked_example_size_32_at_60_Nm():
    """The catalogue's example (size 32, T = 60 N m, in the middle range): phi = T1/K1 + (T - T1)/K2, printed as
    7.15e-4 rad = 2.5 arcmin; 1e-3 relative covers the printed three digits."""
    phi = SIZE32.angle(60.0)
    assert phi == pytest.approx(7.15e-4, rel=1e-3)
    assert np.degrees(phi) * 60 == pytest.approx(2.5, abs=0.05)        # arcmin, printed to one decimal


@pytest.mark.parametrize("T, expect", [
    (10.0, 10.0 / 67e3),                                                  # low range: T / K1
    (29.0, 29.0 / 67e3),                                                  # at T1
    (80.0, 29.0 / 67e3 + 51.0 / 110e3),                                   # middle range
    (150.0, 29.0 / 67e3 + 79.0 / 110e3 + 42.0 / 120e3),                   # high range
])
def test_angle_is_the_closed_form_of_each_range(T, expect):
    """Closed form of each range (module docstring); exact up to round-off (1e-14 relative)."""
    assert SIZE32.angle(T) == pytest.approx(expect, rel=1e-14)


@pytest.mark.parametrize("limit", [29.0, 108.0])
def test_angle_is_continuous_at_the_limit_torques_and_the_slope_changes_there(limit):
    """phi is continuous at T1 and T2: a step of 2 eps across the limit moves it by at most 2 eps / K1 (the
    softest range); the slope on either side is the catalogue's stiffness of that range (1e-6: eps / T)."""
    eps = 1e-6
    lo, hi = SIZE32.angle(limit - eps), SIZE32.angle(limit + eps)
    assert abs(hi - lo) <= 2 * eps / 67e3 * (1 + 1e-9)
    k_below, k_above = (67e3, 110e3) if limit == 29.0 else (110e3, 120e3)
    assert eps / (SIZE32.angle(limit) - lo) == pytest.approx(k_below, rel=1e-6)
    assert eps / (hi - SIZE32.angle(limit)) == pytest.approx(k_above, rel=1e-6)
    assert SIZE32.tangent(limit - eps) == k_below and SIZE32.tangent(limit + eps) == k_above


def test_angle_and_secant_are_symmetric_in_the_sign_of_the_torque():
    """One curve for both directions: phi(-T) = -phi(T) and the secant between -a and -b equals that between
    a and b (exact: the law uses |T|)."""
    T = np.linspace(-200.0, 200.0, 801)
    np.testing.assert_array_equal(SIZE32.angle(-T), -SIZE32.angle(T))
    a, b = np.meshgrid(np.linspace(-150, 150, 31), np.linspace(-150, 150, 29))
    np.testing.assert_allclose(SIZE32.secant(-a, -b), SIZE32.secant(a, b), rtol=1e-12)


def test_secant_between_two_torques_is_the_difference_quotient():
    """What a measurement between two loads sees: from 20 to 60 N m the spring runs 9 N m on K1 and 31 N m on
    K2, so k = 40 / (9/K1 + 31/K2); from 0 to 10 N m, and from -10 to 10 N m, it is K1 (1e-12)."""
    assert SIZE32.secant(20.0, 60.0) == pytest.approx(40.0 / (9.0 / 67e3 + 31.0 / 110e3), rel=1e-12)
    assert SIZE32.secant(0.0, 10.0) == pytest.approx(67e3, rel=1e-12)
    assert SIZE32.secant(-10.0, 10.0) == pytest.approx(67e3, rel=1e-12)
    assert SIZE32.secant(60.0, 60.0) == 110e3                            # coinciding torques: the tangent
    assert 67e3 < SIZE32.secant(0.0, 300.0) < 120e3                      # a secant lies between K1 and K3


@pytest.mark.parametrize("limits, stiff", [((29.0, 29.0), (1.0, 2.0, 3.0)), ((-1.0, 5.0), (1.0, 2.0, 3.0)),
                                           ((1.0, 5.0), (1.0, 0.0, 3.0))])
def test_bad_catalogue_data_is_refused(limits, stiff):
    with pytest.raises(ValueError, match="StrainWaveTorsion"):
        StrainWaveTorsion(limits, stiff)
