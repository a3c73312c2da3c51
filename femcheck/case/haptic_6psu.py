"""The 6-PSU haptic device case (seed 000 §4; conventions in docs/conventions.md).

Each TOML table becomes one frozen dataclass; :class:`Haptic6PSUCase` holds them all. Derived
geometric quantities (angles in rad, base points) are properties, computed from the stored
values, never stored twice.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from femcheck.case.haptic_6psu_solid import SolidModel
from femcheck.case.solver_options import SolverOptions
from femcheck.case.schema import CaseMeta as Meta, CaseRecord, Material, build_sectioned, option, quantity

CASE_KIND = "haptic_6psu"


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
class ModelOptions:
    joint_rotations: Literal["rigid", "released"] = option(
        "rigid", doc="rigid: S/U joints carry moments (paper as published); released: ideal joints")
    beam_shear: bool = option(False, doc="add Timoshenko shear L/(kappa G A) to the lateral beam terms")
    hertz_force: Literal["own_joint_force_at_test_load"] = option(
        "own_joint_force_at_test_load", doc="Hertz linearization force (docs/conventions.md §6)")
    law_scale: LawScale = LawScale()
    leg_scale: LegScale = LegScale()
    joint_rotation_compliance_rad_per_Nm: float = quantity(
        "rad/(N m)", check="nonnegative", default=0.0,
        doc="compliance of every passive S/U joint rotation for rigid joints (joint_rotation_release; 0 = rigid)")
    reading: ReadingEffects = ReadingEffects()


@dataclass(frozen=True)
class Geometry:
    base_radius_m: float = quantity("m", doc="R_b, radius of the circle of the guideway clamps A_i")
    base_pair_half_angle_deg: float = quantity("deg", check="nonnegative", doc="alpha_b")
    platform_radius_m: float = quantity("m", doc="R_p, radius of the circle of the U-joint centres C_i")
    platform_pair_half_angle_deg: float = quantity("deg", check="nonnegative", doc="alpha_p")
    platform_pair_rotation_deg: float = quantity("deg", check="any", doc="only -60 or +60 supported")
    base_height_m: float = quantity("m", check="any", doc="z of the clamp points A_i")
    guideway_direction: tuple[float, float, float] = quantity("-", check="any", doc="unit rail direction e")
    proximal_link_length_m: float = quantity("m", doc="L2, B_i to C_i")
    tcp_offset_m: tuple[float, float, float] = quantity("m", check="any", doc="TCP in the platform frame")
    platform_rpy_deg: tuple[float, float, float] = quantity("deg", check="any", doc="platform orientation")
    rail_length_m: float = quantity("m", doc="usable rail length (upper slider limit)")
    min_slider_position_m: float = quantity("m", check="nonnegative", doc="lower slider limit")

    def __post_init__(self):
        e = np.asarray(self.guideway_direction)
        if abs(np.linalg.norm(e) - 1.0) > 1e-9:
            raise ValueError(f"guideway_direction: |e| = {np.linalg.norm(e):.6g}; expected a unit vector")
        if abs(abs(self.platform_pair_rotation_deg) - 60.0) > 1e-9:
            raise ValueError(f"platform_pair_rotation_deg: = {self.platform_pair_rotation_deg}; expected -60 or +60")
        if self.min_slider_position_m >= self.rail_length_m:
            raise ValueError("min_slider_position_m: must be smaller than rail_length_m")


@dataclass(frozen=True)
class Workspace:
    nominal_tcp_m: tuple[float, float, float] = quantity("m", check="any", doc="P0, centre of the test cube")
    cube_edge_m: float = quantity("m", doc="edge of the test cube")
    corner_signs: tuple[tuple[int, int, int], ...] = quantity("-", check="any", doc="P1..P8 sign triples")

    def __post_init__(self):
        if len(self.corner_signs) != 8 or any(abs(s) != 1 for row in self.corner_signs for s in row):
            raise ValueError("corner_signs: expected 8 triples of +-1")
        if len({tuple(r) for r in self.corner_signs}) != 8:
            raise ValueError("corner_signs: the 8 corners must be distinct")


@dataclass(frozen=True)
class Loads:
    directions: tuple[str, ...] = option(doc="TCP load directions (+x, -x, +y, -y, +z, -z)")
    simplified_test_N: float = quantity("N")
    simplified_preload_N: float = quantity("N", check="nonnegative")
    detailed_test_N: float = quantity("N")
    detailed_preload_N: float = quantity("N", check="nonnegative")

    def __post_init__(self):
        bad = [d for d in self.directions if d not in ("+x", "-x", "+y", "-y", "+z", "-z")]
        if bad:
            raise ValueError(f"directions: {bad[0]!r} is not one of +x, -x, +y, -y, +z, -z")


@dataclass(frozen=True)
class Guideway:
    """Rectangular bar, cantilever clamped at A_i and loaded at the slider B_i (length s_i)."""
    material: Material = option(doc="material name")
    width_radial_m: float = quantity("m", doc="b, along local x_A (radial)")
    depth_tangential_m: float = quantity("m", doc="h, along local y_A (tangential)")


@dataclass(frozen=True)
class ProximalLink:
    """Round tube from B_i to C_i."""
    material: Material = option(doc="material name")
    outer_diameter_m: float = quantity("m")
    inner_diameter_m: float = quantity("m", check="nonnegative")

    def __post_init__(self):
        if self.inner_diameter_m >= self.outer_diameter_m:
            raise ValueError(f"inner_diameter_m: = {self.inner_diameter_m}; expected < outer_diameter_m = {self.outer_diameter_m}")


@dataclass(frozen=True)
class SphericalJoint:
    """Ball on a seat at B_i (Hertz point contact)."""
    ball_radius_m: float = quantity("m")
    ball_material: Material = option()
    seat_material: Material = option()
    seat_curvature_1_per_m: float = quantity("1/m", check="any", doc="0 flat; concave seat of radius Rs: -1/Rs")
    min_contact_force_N: float = quantity("N", doc="floor of the Hertz linearization force")

    def __post_init__(self):
        if 1.0 / self.ball_radius_m + self.seat_curvature_1_per_m <= 0:
            raise ValueError("seat_curvature_1_per_m: 1/R_ball + curvature must be > 0 (seat radius must exceed ball radius)")


@dataclass(frozen=True)
class UniversalJoint:
    """Cross pins in yoke bores at C_i (Hertz line contact + simply supported pin bending)."""
    pin_radius_m: float = quantity("m")
    contact_length_m: float = quantity("m")
    pin_span_m: float = quantity("m")
    pin_material: Material = option()
    bore_material: Material = option()


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
class Actuation:
    """DC motor -> capstan -> cable -> slider."""
    cable_diameter_m: float = quantity("m")
    cable_modulus_Pa: float = quantity("Pa")
    cable_length_m: float = quantity("m")
    shaft_diameter_m: float = quantity("m")
    shaft_length_m: float = quantity("m")
    shaft_G_Pa: float = quantity("Pa")
    capstan_radius_m: float = quantity("m")
    fe: ActuationFE = ActuationFE()


@dataclass(frozen=True)
class Measurement:
    dial_resolution_m: float = quantity("m")
    noise_sigma_m: float = quantity("m", check="nonnegative")
    trials: int = quantity("-")


@dataclass(frozen=True)
class Haptic6PSUCase(CaseRecord):
    """A validated 6-PSU device case. Immutable; variants via :meth:`with_params`."""

    meta: Meta
    model: ModelOptions
    materials: tuple[Material, ...]
    geometry: Geometry
    workspace: Workspace
    loads: Loads
    guideway: Guideway
    proximal_link: ProximalLink
    spherical_joint: SphericalJoint
    universal_joint: UniversalJoint
    actuation: Actuation
    measurement: Measurement
    solid: SolidModel = SolidModel()
    solver: SolverOptions = SolverOptions()

    kind = CASE_KIND

    def material(self, name: str) -> Material:
        for m in self.materials:
            if m.name == name:
                return m
        raise KeyError(name)

    # -- derived geometry (docs/conventions.md §2), all SI --------------------------------------------
    @property
    def n_chains(self) -> int:
        return 6

    @property
    def base_angles_rad(self) -> np.ndarray:
        """(6,) theta_b,i = 120 k + s_i alpha_b, rad."""
        i = np.arange(6)
        s = np.where(i % 2 == 0, -1.0, 1.0)
        return np.deg2rad(120.0 * (i // 2) + s * self.geometry.base_pair_half_angle_deg)

    @property
    def platform_angles_rad(self) -> np.ndarray:
        """(6,) theta_p,i = 120 k + s_i (60 - alpha_p) (rotation -60 deg; +60 gives the same set), rad."""
        i = np.arange(6)
        s = np.where(i % 2 == 0, -1.0, 1.0)
        return np.deg2rad(120.0 * (i // 2) + s * (60.0 - self.geometry.platform_pair_half_angle_deg))

    @property
    def base_points(self) -> np.ndarray:
        """(6, 3) clamp points A_i in U, m."""
        g, th = self.geometry, self.base_angles_rad
        return np.stack([g.base_radius_m * np.cos(th), g.base_radius_m * np.sin(th), np.full(6, g.base_height_m)], axis=1)

    @property
    def platform_points(self) -> np.ndarray:
        """(6, 3) U-joint centres C_i in the platform frame P, m."""
        g, th = self.geometry, self.platform_angles_rad
        return np.stack([g.platform_radius_m * np.cos(th), g.platform_radius_m * np.sin(th), np.zeros(6)], axis=1)


SECTIONS = {"solver": SolverOptions, 
    "meta": Meta, "model": ModelOptions, "geometry": Geometry, "workspace": Workspace, "loads": Loads,
    "guideway": Guideway, "proximal_link": ProximalLink, "spherical_joint": SphericalJoint,
    "universal_joint": UniversalJoint, "actuation": Actuation, "measurement": Measurement,
    "solid": SolidModel,
}
#: sections that may be absent (their fields all have defaults)
OPTIONAL_SECTIONS = ("solver", "meta", "model", "solid")


def build(raw: dict, path) -> Haptic6PSUCase:
    """Validate a parsed TOML document into a :class:`Haptic6PSUCase` (errors name file and key)."""
    return build_sectioned(Haptic6PSUCase, raw, path, SECTIONS, OPTIONAL_SECTIONS)
