"""The drive of a parallel device's actuated joint as finite elements, condensed onto the joint's freedom.

The analytical chain takes the drive as one spring (:class:`femcheck.case.parallel_device.Drive`): axial =
a cable strand in series with the motor shaft's torsion seen through the capstan (and gearbox), torsional =
the shaft's torsion times the gear ratio squared. The device FE instead assembles the parts the case
describes and condenses them (Schur complement) onto the joint's freedom, so a mistake in that law's form
(a missing r², a ratio squared the wrong way) moves the analytical model only:

* **motor shaft**: one 3D beam element (:mod:`femcheck.fe.beam`, circle of ``shaft_diameter_m``, shear modulus
  ``shaft_G_Pa``, length ``shaft_length_m``) along the motor axis a; the rotor end is held (the position loop
  taken ideal, as in the analytical model), the other end turns about a only (bearings);
* **gearbox** (``gear_ratio`` n): rigid, a kinematic map: the shaft's output end turns n times the output;
* **capstan** (axial drive, radius ``capstan_radius_m`` r): a rigid lever, its tangent point moves φ a × (r n_c);
* **cable** (axial drive): one truss strand (:mod:`femcheck.fe.cable`, E_c π d_c² / 4, free length
  ``cable_length_m``, no pretension: the strand runs along the joint axis, so the geometric term does not act
  along it) from the capstan's tangent point to the slider.

With a given ``stiffness`` the case describes no parts: the FE then takes that spring as it is (the law is
shared, and coverage reports it as such).
"""
from __future__ import annotations

import math

import numpy as np

from femcheck.fe.beam import BeamSection, assemble_beam_stiffness
from femcheck.fe.cable import cable_stiffness, strand_geometry

#: shaft bending plays no part (bearings hold it); any E with G = E / (2 (1 + nu)) for a steel-like nu
_NU_SHAFT = 0.3


def has_elements(drive) -> bool:
    """Whether the case describes the drive's parts (a shaft, and a cable for an axial drive)."""
    return drive.stiffness is None


def _shaft_torsion(drive) -> float:
    """G J / L (N m/rad) of the motor shaft from its beam element: the rotor end held, the other end turned
    about the shaft axis."""
    G = float(drive.shaft_G_Pa)
    a = np.array([0.0, 0.0, 1.0])
    Kb = assemble_beam_stiffness(np.array([[0.0, 0.0, 0.0], [0.0, 0.0, float(drive.shaft_length_m)]]), [[0, 1]],
                                 2.0 * G * (1.0 + _NU_SHAFT), G, BeamSection.circle(float(drive.shaft_diameter_m)),
                                 orientation=np.array([1.0, 0.0, 0.0]), shear=False).toarray()
    t = np.zeros(12)
    t[9:12] = a
    return float(t @ Kb @ t)


def drive_stiffness(drive) -> float:
    """Stiffness of the drive's elements at the actuated joint (N/m along a P joint, N m/rad about an R joint),
    condensed from the assembled parts (module doc); the case's ``stiffness`` where it gives no parts."""
    if not has_elements(drive):
        return float(drive.stiffness)
    n = float(drive.gear_ratio)
    k_shaft = _shaft_torsion(drive) * n * n     # the shaft end turns n x the gearbox output
    if drive.law == "torsional":
        return k_shaft
    # axial: unknowns z = [u_slider (3), phi_capstan]; the slider moves along e, the strand along e from the
    # capstan's tangent point (capstan centre c = -l e - r m, axis a = e x m: its tangent point turns to +-e)
    e, m = np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])
    a = np.cross(e, m)
    r, length = float(drive.capstan_radius_m), float(drive.cable_length_m)
    EA = float(drive.cable_modulus_Pa) * math.pi * float(drive.cable_diameter_m) ** 2 / 4.0
    P = -length * e
    ev, L = strand_geometry(np.stack([P, np.zeros(3)]), [[0, 1]])
    Ke = cable_stiffness(ev, L, EA, 0.0)[0]
    M = np.zeros((6, 4))
    M[:3, 3] = np.cross(a, r * m)                # tangent point P = c + r m moves by phi a x (r m)
    M[3:, :3] = np.eye(3)
    K = M.T @ Ke @ M
    K[3, 3] += k_shaft
    Kss, Ksp, Kpp = K[:3, :3], K[:3, 3:], K[3:, 3:]
    K_S = Kss - Ksp @ np.linalg.solve(Kpp, Ksp.T)
    return float(e @ K_S @ e)
