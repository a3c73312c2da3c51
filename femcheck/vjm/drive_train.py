"""Joint stiffness synthesis from drive-train components as springs in series (seed 003 sec. 3).

A joint's transmission (motor -> [timing belt] -> harmonic reducer -> link) is a chain of torsion springs
in series. Each component's stiffness is stated on its own output side and carried to the joint output
through the speed-reduction ratios of the components after it: a spring ``k`` behind a total ratio ``r``
acts at the output as ``r^2 k``. The joint stiffness is (seed 003 eq. 21)::

    K_theta = 1 / sum_j 1 / (k_j prod_{l after j} r_l^2)

which gives the seed's rules: motor ``lambda^2 lambda_t^2 K_m``, belt ``lambda^2 K_t``, reducer ``K_r``.

Component stiffnesses (all N m/rad):

* AC servo motor, from the torsional natural frequency ``omega_0 = 1/t = (1/2 pi) sqrt(K_m/J_m)``
  (seed 003 eqs. 16-17): ``K_m = 4 pi^2 J_m / t^2`` with the mechanical time constant t (s) and rotor inertia
  J_m (kg m^2).
* Harmonic reducer (seed 003 eqs. 18-19): output-side stiffness ``K_r = T / phi`` (= lambda^2 K_in).
* Timing belt (seed 003 eq. 20)::

      K_t = 1 / ( L / (a R^2 E A) + eta / (B R^2) )

  with belt length L (m), tension factor a (-), driving-pulley radius R (m), belt modulus E (Pa), tooth-root
  cross-section A (m^2), width B (m) and tooth-form factor eta (m^3/N). The flattened fraction in the seed's
  text can also be read as ``L a / (R^2 E A)``; only ``L / (a R^2 E A)`` reproduces the seed's own numbers
  (123.75 and 78.49 N m/rad for joints 3 and 5 from its Table 4), so that reading is used.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def motor_stiffness(time_constant_s: float, rotor_inertia_kg_m2: float) -> float:
    """K_m = 4 pi^2 J_m / t^2, N m/rad (seed 003 eq. 17)."""
    return 4.0 * math.pi**2 * rotor_inertia_kg_m2 / time_constant_s**2


def reducer_stiffness(torque_Nm: float, rotation_rad: float) -> float:
    """K_r = T / phi, output side, N m/rad (seed 003 eq. 19)."""
    return torque_Nm / rotation_rad


def timing_belt_stiffness(length_m: float, tension_factor: float, pulley_radius_m: float, modulus_Pa: float,
                          section_m2: float, width_m: float, tooth_factor_m3_per_N: float) -> float:
    """K_t = 1 / (L/(a R^2 E A) + eta/(B R^2)), N m/rad (seed 003 eq. 20; reading discussed in the module doc)."""
    R2 = pulley_radius_m**2
    return 1.0 / (length_m / (tension_factor * R2 * modulus_Pa * section_m2) + tooth_factor_m3_per_N / (width_m * R2))


@dataclass(frozen=True)
class DriveComponent:
    """One spring of a joint's drive train: ``name``, ``stiffness_Nm_per_rad`` on its own output side and the
    speed-reduction ``ratio`` it applies (input speed / output speed; 1 for a motor)."""

    name: str
    stiffness_Nm_per_rad: float
    ratio: float = 1.0


def reflected_stiffnesses(components: tuple[DriveComponent, ...] | list[DriveComponent]) -> np.ndarray:
    """Each component's stiffness at the joint output, N m/rad: ``k_j prod_{l > j} r_l^2`` (seed 003 sec. 3.2).

    ``components`` are ordered from the motor to the joint output.
    """
    k = np.array([c.stiffness_Nm_per_rad for c in components], dtype=float)
    r = np.array([c.ratio for c in components], dtype=float)
    after = np.append(np.cumprod((r**2)[::-1])[::-1][1:], 1.0)   # prod of r_l^2 for l > j
    return k * after


def joint_stiffness(components) -> float:
    """Series joint stiffness K_theta = 1 / sum 1/k_j (seed 003 eq. 21), N m/rad."""
    return float(1.0 / np.sum(1.0 / reflected_stiffnesses(components)))
