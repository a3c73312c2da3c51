"""Frictional rotation law of the contact joints of the detailed FE (joints = ``contact``).

A real ball-in-seat or pin-in-bore joint carries a moment only through friction: frictionless contact
forces on a sphere (a cylinder) are normal to it and pass through its centre (its axis), so they have no
moment about B (about the pin axis). With Coulomb friction μ the joint *sticks* until the friction force
saturates, then *slides* at a constant friction moment (elastic–perfectly-plastic per joint rotation):

==================  ==========================  ========================================================
rotation            slip moment M_s (N m)         stick stiffness k (N m/rad)
==================  ==========================  ========================================================
ball tilt (x_U,y_U)  μ_sp F R_b · ρ               k_t R_b², k_t = 8 G* a (Mindlin; Johnson eq. 7.32)
ball spin (z_U)      (3π/16) μ_sp F a            (16/3) G* a³ (torsion of a stuck circular contact, Lubkin)
pin a1, a2 (x_B,y_B) μ_uj F r_pin                k_t,line r_pin², k_t,line = K_UC 2(1-ν)/(2-ν) (Mindlin ratio)
==================  ==========================  ========================================================

F is the force the leg's joint transmits (docs/conventions.md §6), a = (3 F R* / (4 E*))^{1/3} the Hertz radius,
1/G* = (2-ν1)/G1 + (2-ν2)/G2 (Johnson §7.1). ρ (``tilt_slip_ratio``, 1 by the argument above) is the
ratio M / (μ F R_b) that the contact FE of the ball alone measures in full slip
(:func:`femcheck.fe_device.joint_contact.spherical_joint_tilt`); the verification passes it in.
Seat normal = rail direction e = z_U (docs/conventions.md §2), so the spin component is θ_z in frame U.

Load path. Under the test protocol the TCP load grows monotonically along one direction, so every
joint's force and rotation grow in proportion (proportional loading): a joint then sticks or slides
from the start, its rotation keeps its direction, and the incremental elastic–plastic law equals the
*secant* law M = k_sec r, k_sec = min(k, M_s / |r|) (deformation theory). The ball's two tilt
components share one secant (the friction force resists the tilt vector, not each component).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

#: rotation components that carry a friction spring: spherical joint in frame U (tilt x, tilt y, spin
#: z = seat normal), U joint in frame B (pins a1 = x_B, a2 = y_B)
SP_ROTATIONS = (3, 4, 5)
UJ_ROTATIONS = (3, 4)


@dataclasses.dataclass(frozen=True)
class JointFriction:
    """Friction data of the two joint types (SI): μ_sp, μ_uj, ball radius R_b, pin radius r_pin, Hertz
    E* and R* of the ball, G* (Mindlin), K_UC (N/m, line contact) and Poisson ratio of the pin/bore pair,
    ``tilt_slip_ratio`` ρ (FE-measured, default 1)."""

    mu_sp: float
    mu_uj: float
    ball_radius_m: float
    pin_radius_m: float
    E_star_Pa: float
    R_star_m: float
    G_star_Pa: float
    K_uc_N_per_m: float
    nu_pin: float
    tilt_slip_ratio: float = 1.0

    def with_tilt_slip_ratio(self, ratio: float) -> "JointFriction":
        return dataclasses.replace(self, tilt_slip_ratio=float(ratio))

    def contact_radius(self, F) -> np.ndarray:
        """Hertz contact radius a (m) of the ball under F (N): (3 F R* / (4 E*))^{1/3}."""
        return (3.0 * np.asarray(F, float) * self.R_star_m / (4.0 * self.E_star_Pa)) ** (1.0 / 3.0)

    def slip_moments(self, F) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M_tilt, M_spin, M_pin) (N m), each shaped like F (N): the table of the module doc."""
        F = np.asarray(F, float)
        a = self.contact_radius(F)
        return (self.mu_sp * F * self.ball_radius_m * self.tilt_slip_ratio,
                3.0 * math.pi / 16.0 * self.mu_sp * F * a,
                self.mu_uj * F * self.pin_radius_m)

    def stick_stiffness(self, F) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(k_tilt, k_spin, k_pin) (N m/rad): stuck-contact rotational stiffness (module doc)."""
        a = self.contact_radius(F)
        k_t = 8.0 * self.G_star_Pa * a
        k_line = self.K_uc_N_per_m * 2.0 * (1.0 - self.nu_pin) / (2.0 - self.nu_pin)
        return k_t * self.ball_radius_m**2, 16.0 / 3.0 * self.G_star_Pa * a**3, np.broadcast_to(
            k_line * self.pin_radius_m**2, np.shape(a)).copy()

    def secant_stiffness(self, F, r_sp, r_uj, stick=None) -> tuple[np.ndarray, np.ndarray]:
        """Secant rotational stiffnesses (N m/rad) for leg forces F (n,) N and joint rotations r_sp (n, 3)
        (frame U: tilt x, tilt y, spin z) and r_uj (n, 2) (frame B: a1, a2), rad -> ((n, 3), (n, 2)).
        ``stick``: (k_tilt, k_spin, k_pin) to use instead of the closed forms of :meth:`stick_stiffness`
        (the contact FE's measured stick stiffnesses, :mod:`femcheck.fe_device.joint_laws`)."""
        Mt, Ms, Mp = self.slip_moments(F)
        kt, ks, kp = self.stick_stiffness(F) if stick is None else stick
        tilt = np.linalg.norm(r_sp[:, :2], axis=1)
        k_sp = np.empty((len(F), 3))
        k_sp[:, :2] = _secant(kt, Mt, tilt)[:, None]
        k_sp[:, 2] = _secant(ks, Ms, np.abs(r_sp[:, 2]))
        kp = np.asarray(kp, float)
        k_uj = _secant(kp[:, None] if kp.ndim == 1 else kp, Mp[:, None], np.abs(r_uj))
        return k_sp, k_uj


def _secant(k_stick, M_slip, r):
    """min(k, M_s / |r|) with the stick value where r = 0."""
    r = np.asarray(r, float)
    with np.errstate(divide="ignore"):
        return np.where(r * k_stick > M_slip, M_slip / np.where(r > 0, r, 1.0), k_stick)


def joint_friction(case, tilt_slip_ratio: float = 1.0, springs=None) -> JointFriction:
    """The :class:`JointFriction` of ``case`` (materials, radii, μ from ``[solid.*_joint] friction``). E*, R* and
    K_UC are the device FE's own (``springs``, default :func:`femcheck.fe_device.contact_scales.device_springs`,
    from the materials), never the analytical model's: the slip moments must not move with a law under test."""
    from femcheck.fe_device.contact_scales import device_springs
    sj, uj, so = case.spherical_joint, case.universal_joint, case.solid
    sp = springs or device_springs(case)
    m1, m2 = sj.ball_material, sj.seat_material
    G_star = 1.0 / ((2.0 - m1.nu) / m1.G_Pa + (2.0 - m2.nu) / m2.G_Pa)
    return JointFriction(mu_sp=so.spherical_joint.friction, mu_uj=so.universal_joint.friction,
                         ball_radius_m=sj.ball_radius_m,
                         pin_radius_m=uj.pin_radius_m if uj is not None else float("nan"),
                         E_star_Pa=sp.E_star_sp, R_star_m=sp.R_star_sp,
                         G_star_Pa=G_star, K_uc_N_per_m=1.0 / sp.c_uc,
                         nu_pin=uj.pin_material.nu if uj is not None else float("nan"),
                         tilt_slip_ratio=tilt_slip_ratio)
