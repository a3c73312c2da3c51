"""The device FE's own contact scales and closed-form springs, from materials, geometry and loads only.

The FE checks the analytical laws, so it must not take any of its set-up from them. Everything the contact
FE of a joint and the device FE derive from a contact law is computed here, from the case's Young's moduli,
Poisson ratios, radii, lengths and loads, and never from :func:`femcheck.chain.device_parameters`,
``[model.law_scale]`` or :mod:`femcheck.compliance` (the analytical model's laws). A mistake in an analytical
law, or a law mutation of the coverage, therefore leaves every FE input unchanged:

* contact modulus and radius of the ball on its seat (Johnson §4.2): 1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂,
  1/R* = 1/R_b + κ_seat;
* the Hertz patch the contact FE expects (Johnson eqs. 4.22–4.23): its radius a(F) = (3 F R* / (4 E*))^{1/3} grades the ball's mesh, and its approach
  δ(F) = (3 F / (4 E* √R*))^{2/3} (:func:`femcheck.fe_device.loads.hertz_approach`) picks the candidate contact
  points, the initial active set and the penetration tolerance;
* the springs the device FE uses where it has no element of its own (:class:`DeviceSprings`): the ball's
  Hertz spring without the joint contact FE, the pin-in-bore line contact K_UC = π l E*/2 and the pin bending
  K_UB = 48 E (π r⁴/4) / L_u³ without it (seed 000 eqs. 36–41), the actuation as one cable strand in series with
  the shaft torsion through the capstan without the actuation FE (seed 000 eq. 44);
* the frictional slip moments (:mod:`.joint_friction`), whose spin term needs a(F).

These are estimates and idealized springs of the FE, written from the materials; that they coincide with the
analytical laws for an unmutated case is what ``verify`` then checks, not an input.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np


def contact_modulus(m1, m2) -> float:
    """E* (Pa) of two isotropic bodies (case materials with ``E_Pa``, ``nu``): 1/E* = Σ (1 − ν²)/E."""
    return 1.0 / ((1.0 - m1.nu * m1.nu) / m1.E_Pa + (1.0 - m2.nu * m2.nu) / m2.E_Pa)


@dataclasses.dataclass(frozen=True)
class DeviceSprings:
    """The device FE's closed-form springs and contact constants (SI; module doc).

    Ball on seat: ``E_star_sp`` (Pa), ``R_star_sp`` (m), ``F_min_sp`` (N, the linearization floor); U joint:
    ``c_uc`` = 1/K_UC, ``c_ub`` = 1/K_UB (m/N), ``E_star_uj`` (Pa, pin on bore); actuation: ``c_act`` (m/N,
    cable strand plus shaft torsion at the cable). The attribute names are those of
    :class:`femcheck.chain.DeviceParameters` that :func:`femcheck.fe_device.loads.solve_state` reads."""

    E_star_sp: float
    R_star_sp: float
    F_min_sp: float
    E_star_uj: float
    c_uc: float
    c_ub: float
    c_act: float

    def ball_patch_radius(self, F) -> np.ndarray:
        """Expected contact radius a (m) of the ball under F (N): (3 F R* / (4 E*))^{1/3}."""
        return (3.0 * np.asarray(F, float) * self.R_star_sp / (4.0 * self.E_star_sp)) ** (1.0 / 3.0)

    def ball_approach(self, F) -> np.ndarray:
        """Expected approach δ (m) of the ball under F (N) (Johnson eq. 4.23)."""
        from femcheck.fe_device.loads import hertz_approach
        return hertz_approach(F, self.E_star_sp, self.R_star_sp)

    def axial_compliance(self, joint: str, loads_N) -> float:
        """Expected axial compliance (m/N) of ``joint`` between the smallest and the largest of ``loads_N``:
        the ball's Hertz secant, the U joint's line contact plus pin bending. Scales the contact FE's
        penetration tolerance."""
        F0, F1 = float(min(loads_N)), float(max(loads_N))
        if joint == "spherical":
            d = self.ball_approach(np.array([F0, F1]))
            return float((d[1] - d[0]) / (F1 - F0))
        return self.c_uc + self.c_ub

    def with_law_scale(self, element: str, factor: float) -> "DeviceSprings":
        """These springs with the closed form of ``element`` ('act', 'sp', 'uj') ``factor`` times as compliant, as
        ``[model.law_scale]`` scales the analytical law (Hertz through E*^(-3/2)). Only for the coverage, which asks
        what the FE would show if the mistake were in a closed form the FE restates
        (:func:`closed_form_elements`); the FE itself never reads ``[model.law_scale]``."""
        if element == "act":
            return dataclasses.replace(self, c_act=self.c_act * factor)
        if element == "sp":
            return dataclasses.replace(self, E_star_sp=self.E_star_sp * factor ** -1.5)
        if element == "uj":
            return dataclasses.replace(self, c_uc=self.c_uc * factor, c_ub=self.c_ub * factor)
        raise ValueError(f"element {element!r}: the device FE has no closed form for it (expected act, sp or uj)")


def closed_form_elements(case, joint_laws=None) -> frozenset:
    """The chain elements ('act', 'sp', 'uj') that the detailed device FE models by a closed form of its own (the
    same law restated from the materials, so a mistake in the law's form is not seen): the actuation unless
    ``[actuation.fe] model = "elements"``, each joint without a contact-FE-measured law in ``joint_laws``."""
    out = set()
    if case.actuation.fe.model != "elements":
        out.add("act")
    if joint_laws is None or joint_laws.spherical is None:
        out.add("sp")
    if joint_laws is None or joint_laws.universal is None:
        out.add("uj")
    return frozenset(out)


def device_springs(case) -> DeviceSprings:
    """The :class:`DeviceSprings` of a 6-PSU ``case`` from its materials and geometry (module doc). A joint
    specimen of another device (:class:`femcheck.parallel.joint_specimen.JointSpecimen`) may lack the ball, the
    pins or the actuation: their springs are then NaN (no FE step of that specimen reads them)."""
    sj, uj, act = case.spherical_joint, case.universal_joint, getattr(case, "actuation", None)
    nan = float("nan")
    E_sp = R_sp = F_min = E_uj = K_uc = K_ub = c_act = nan
    if sj is not None:
        E_sp = contact_modulus(sj.ball_material, sj.seat_material)
        R_sp = 1.0 / (1.0 / float(sj.ball_radius_m) + float(sj.seat_curvature_1_per_m))
        F_min = float(sj.min_contact_force_N)
    if uj is not None:
        E_uj = contact_modulus(uj.pin_material, uj.bore_material)
        K_uc = math.pi * float(uj.contact_length_m) * E_uj / 2.0
        K_ub = 48.0 * uj.pin_material.E_Pa * (math.pi * float(uj.pin_radius_m) ** 4 / 4.0) / float(uj.pin_span_m) ** 3
    if act is not None:
        k_cable = act.cable_modulus_Pa * math.pi * float(act.cable_diameter_m) ** 2 / 4.0 / act.cable_length_m
        K_rotor = act.shaft_G_Pa * math.pi * float(act.shaft_diameter_m) ** 4 / 32.0 / act.shaft_length_m
        k_motor = K_rotor / float(act.capstan_radius_m) ** 2
        c_act = 1.0 / k_cable + 1.0 / k_motor
    return DeviceSprings(E_star_sp=E_sp, R_star_sp=R_sp, F_min_sp=F_min, E_star_uj=E_uj,
                         c_uc=1.0 / K_uc, c_ub=1.0 / K_ub, c_act=c_act)
