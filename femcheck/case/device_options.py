"""Options of a device case beyond its legs: what coverage, diagnosis, the device FE and the simulated
experiment read (``[model.law_scale]``, ``[model.leg_scale]``, ``[model.reading]``, ``[actuation.fe]``,
``[measurement]``). Sections of :mod:`femcheck.case.parallel_device`; the 6-PSU reference case sets them all.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from femcheck.case.schema import option, quantity


@dataclass(frozen=True)
class LawScale:
    """Multipliers of each element's compliance *law* (``femcheck coverage`` mutates them; 1 = the law as written).

    Applied where the law is defined (:func:`femcheck.chain.device_parameters`), so the analytical chain and
    every FE path that reuses the law see the same change, while a meshed part (which does not use the law)
    does not: that difference is what verification can detect.
    """

    lg: float = quantity("-", default=1.0, doc="guideway cantilever compliance (via E and G of the law)")
    act: float = quantity("-", default=1.0, doc="actuation compliance c_act (cable + motor shaft)")
    sp: float = quantity("-", default=1.0, doc="spherical-joint Hertz compliance (via E* of the law)")
    prox: float = quantity("-", default=1.0, doc="proximal-link tube compliance (via E and G of the law)")
    uj: float = quantity("-", default=1.0, doc="universal-joint line contact + pin bending compliance")


_SIX = tuple[float, float, float, float, float, float]
_ONES = (1.0,) * 6


@dataclass(frozen=True)
class LegScale:
    """Per-leg factors on each element's compliance in the chain (``[model.leg_scale]``; 1 = the case's formula).

    Where ``law_scale`` changes a law for every leg and every FE path that reuses it, a leg scale is what a
    diagnosis found in the built device: one softer spherical joint in leg 2, say. It multiplies the element's
    compliance of chain i in :func:`femcheck.chain.evaluate` (so ``stiffness``, ``map``, ``sweep`` and
    ``diagnose`` see it); the FE paths do not, since a leg scale is not a law they share.
    """

    lg: _SIX = quantity("-", check="nonnegative", default=_ONES, doc="guideway compliance factor of legs 0..5")
    act: _SIX = quantity("-", check="nonnegative", default=_ONES, doc="actuation compliance factor of legs 0..5")
    sp: _SIX = quantity("-", check="nonnegative", default=_ONES, doc="spherical-joint compliance factor of legs 0..5")
    prox: _SIX = quantity("-", check="nonnegative", default=_ONES, doc="proximal-link compliance factor of legs 0..5")
    uj: _SIX = quantity("-", check="nonnegative", default=_ONES, doc="universal-joint compliance factor of legs 0..5")

    def array(self) -> np.ndarray:
        """(6, 5) factors, columns in the order of ``femcheck.chain.ELEMENTS``."""
        return np.array([self.lg, self.act, self.sp, self.prox, self.uj], float).T


@dataclass(frozen=True)
class ReadingEffects:
    """What a reading adds to the elastic deflection (``[model.reading]``): TCP friction, a dead band, the dial
    frame. Each is the diagnosis effect of the same name (``femcheck.diagnose.effects``), held at a fixed value;
    the measured-data paths (``diagnose``) apply them, the stiffness matrix does not contain them."""

    friction_N: float = quantity("N", check="nonnegative", default=0.0,
                                 doc="friction force reflected to the TCP (friction_hysteresis)")
    clearance_gap_m: tuple[float, float, float] = quantity("m", check="nonnegative", default=(0.0, 0.0, 0.0),
                                                           doc="dead band along x, y, z (clearance)")
    clearance_closing_force_N: float = quantity("N", default=4.0, doc="force that closes 63 % of the dead band")
    sensor_rotation_rad: tuple[float, float, float] = quantity("rad", check="any", default=(0.0, 0.0, 0.0),
                                                               doc="rotation vector of the dial frame (sensor_misalignment)")


@dataclass(frozen=True)
class ActuationFE:
    """How the device FE models the actuation (``[actuation.fe]``; :mod:`femcheck.fe_device.actuation_fe`).

    ``model = "law"`` (default): the FE takes the actuation spring 1/c_act from eq. 44 (the law the analytical
    chain uses, so the FE does not check it). ``"elements"``: the FE assembles the motor shaft (beam, torsion),
    the capstan and idler (rigid levers of radius ``capstan_radius_m``) and pretensioned cable strands, and
    condenses them to the slider's axial DOF at each leg's slider position.
    """

    model: Literal["law", "elements"] = option("law", doc="law: eq. 44 spring (shared with the analytical "
                                                          "model); elements: shaft + capstan + cable FE")
    layout: Literal["closed_loop", "single_strand"] = option(
        "closed_loop", doc="closed_loop: capstan - slider - idler - capstan, both strands pretensioned (the "
                           "case's cable_length_m is the loop's free length); single_strand: eq. 44's one strand "
                           "of length cable_length_m, the return side held at constant force")
    cable_pretension_N: float = quantity("N", default=50.0, doc="tau, tension of every strand at rest")
    idler_above_rail_m: float = quantity("m", check="nonnegative", default=0.0,
                                         doc="idler tangent point above the rail's upper end (closed loop)")


@dataclass(frozen=True)
class Measurement:
    dial_resolution_m: float = quantity("m")
    noise_sigma_m: float = quantity("m", check="nonnegative")
    trials: int = quantity("-")


@dataclass(frozen=True)
class DeviceActuation:
    """``[actuation]``: how the device FE models the drives (the drive train itself is each leg's ``drive``)."""
    fe: ActuationFE = ActuationFE()
