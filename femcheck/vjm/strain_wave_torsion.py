"""Torsion of a strain-wave (Harmonic Drive) gear: the catalogue's piecewise-linear torque-torsion law.

Harmonic Drive states the output-side torsional stiffness of a gear with its wave generator blocked as three
linearizations of one curve: ``K1`` over the torque range 0..T1, ``K2`` over T1..T2 and ``K3`` above T2 (the
limit torques T1, T2 per size). The torsion angle at a torque T (N m) is then (the catalogues' "calculation of
the torsion angle", e.g. Harmonic Drive AG, CSD-2A engineering data 1019659 11/2014, eqs. 23.1-23.3)::

    |T| <= T1:        phi = T / K1
    T1 < |T| <= T2:   phi = sign(T) (T1 / K1 + (|T| - T1) / K2)
    |T| > T2:         phi = sign(T) (T1 / K1 + (T2 - T1) / K2 + (|T| - T2) / K3)

continuous at T1 and T2 and odd in T (the catalogue gives one curve for both directions; hysteresis loss and
lost motion, listed separately, are not part of this law). The catalogue's own example, size 32 with
T1 = 29 N m, T2 = 108 N m, K1 = 6.7e4, K2 = 1.1e5 N m/rad at T = 60 N m, gives 7.15e-4 rad (2.5 arcmin).

A measurement that takes the deflection between two loads sees the secant of the law between the two torque
levels, ``(T_b - T_a) / (phi(T_b) - phi(T_a))`` (:meth:`StrainWaveTorsion.secant`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class StrainWaveTorsion:
    """The piecewise-linear torsion law (module docstring). ``limit_torques_Nm`` (T1, T2), N m, 0 < T1 < T2;
    ``stiffness_Nm_per_rad`` (K1, K2, K3), N m/rad, each > 0."""

    limit_torques_Nm: tuple[float, float]
    stiffness_Nm_per_rad: tuple[float, float, float]

    def __post_init__(self):
        t1, t2 = self.limit_torques_Nm
        if not 0 < t1 < t2 < np.inf:
            raise ValueError(f"StrainWaveTorsion.limit_torques_Nm = {self.limit_torques_Nm}; expected 0 < T1 < T2")
        if len(self.stiffness_Nm_per_rad) != 3 or not all(0 < k < np.inf for k in self.stiffness_Nm_per_rad):
            raise ValueError(f"StrainWaveTorsion.stiffness_Nm_per_rad = {self.stiffness_Nm_per_rad}; "
                             "expected three finite values > 0 (K1, K2, K3)")

    @property
    def high_torque_stiffness_Nm_per_rad(self) -> float:
        """K3, the stiffness the catalogues list alone (above T2)."""
        return float(self.stiffness_Nm_per_rad[2])

    def angle(self, torque_Nm) -> np.ndarray:
        """Torsion angle (rad) at ``torque_Nm`` (any shape, N m); odd in the torque."""
        T = np.asarray(torque_Nm, dtype=float)
        (t1, t2), (k1, k2, k3) = self.limit_torques_Nm, self.stiffness_Nm_per_rad
        a = np.abs(T)
        # the three ranges' shares of |T|: up to T1 on K1, T1..T2 on K2, the rest on K3
        phi = np.minimum(a, t1) / k1 + np.clip(a - t1, 0.0, t2 - t1) / k2 + np.maximum(a - t2, 0.0) / k3
        return np.sign(T) * phi

    def tangent(self, torque_Nm) -> np.ndarray:
        """dT/dphi (N m/rad) at ``torque_Nm``: K1, K2 or K3 by the range of |T| (the lower one at a limit)."""
        a = np.abs(np.asarray(torque_Nm, dtype=float))
        (t1, t2), (k1, k2, k3) = self.limit_torques_Nm, self.stiffness_Nm_per_rad
        return np.where(a <= t1, k1, np.where(a <= t2, k2, k3))

    def secant(self, torque_from_Nm, torque_to_Nm) -> np.ndarray:
        """(T_b - T_a) / (phi(T_b) - phi(T_a)), N m/rad, broadcast over both; where the two torques coincide
        (to 1e-12 of the larger), the tangent at T_a."""
        Ta, Tb = np.broadcast_arrays(np.asarray(torque_from_Nm, dtype=float), np.asarray(torque_to_Nm, dtype=float))
        dT = Tb - Ta
        same = np.abs(dT) <= 1e-12 * np.maximum(np.maximum(np.abs(Ta), np.abs(Tb)), 1e-300)
        dphi = self.angle(Tb) - self.angle(Ta)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(same, self.tangent(Ta), dT / np.where(same, 1.0, dphi))
