"""The serial-robot case (VJM; seeds 002 and 003): a DH table, joint stiffnesses and optional extended-VJM tilts.

TOML layout (SI; angles only in keys ending ``_deg``)::

    [meta]            kind = "serial_robot", name
    [model]           vjm = "conventional" | "extended", complementary_stiffness = true | false
    [kinematics]      convention = "standard" | "modified", tool_offset_m = [x, y, z]
    [[joints]]        one table per DH row: a_m, alpha_deg, d_m, theta_offset_deg, and either
                      stiffness_Nm_per_rad or one or more [[joints.drive_train]] components (motor -> output);
                      for the extended VJM tilt_stiffness_Nm_per_rad = [k_x, k_y] and tilt_offset_m
    [gravity]         optional: vector_m_per_s2 (base frame) for the self-weight diagnosis (with joints' mass_kg, com_m)
    [identification]  optional: configurations_deg = [[q1..qn], ...], wrenches = [[fx..mz], ...], rows

Drive-train components (seed 003 sec. 3), ``kind`` =

* ``"motor"``: ``stiffness_Nm_per_rad`` or ``time_constant_s`` + ``rotor_inertia_kg_m2`` (K_m = 4 pi^2 J_m / t^2);
* ``"harmonic_reducer"``: ``ratio`` and ``stiffness_Nm_per_rad`` (output side) or ``torque_Nm`` + ``rotation_rad``;
* ``"timing_belt"``: ``ratio``, ``length_m``, ``tension_factor``, ``pulley_radius_m``, ``modulus_Pa``,
  ``section_m2``, ``width_m``, ``tooth_factor_m3_per_N``;
* ``"spring"``: any other torsion spring, ``stiffness_Nm_per_rad`` and ``ratio``.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Literal

import numpy as np

from femcheck.case.schema import CaseMeta as Meta, CaseRecord, Context, build_section, build_sections, option, quantity
from femcheck.vjm import drive_train as dt
from femcheck.vjm.dh import DHChain
from femcheck.vjm.serial_vjm import SerialVJM

CASE_KIND = "serial_robot"


@dataclass(frozen=True)
class ModelOptions:
    vjm: Literal["conventional", "extended"] = option(
        "conventional", doc="conventional: one torsion spring per joint (seed 003); extended: + two tilts (seed 002)")
    complementary_stiffness: bool = option(True, doc="include K_C of the wrench (seed 002 eq. 5)")


@dataclass(frozen=True)
class Kinematics:
    convention: Literal["standard", "modified"] = option(doc="DH convention: standard or modified (Craig)")
    tool_offset_m: tuple[float, float, float] = quantity("m", check="any", default=(0.0, 0.0, 0.0),
                                                         doc="tool point in the last frame")


_COMPONENT_FIELDS = {
    "motor": ({"stiffness_Nm_per_rad"}, {"time_constant_s", "rotor_inertia_kg_m2"}),
    "harmonic_reducer": ({"stiffness_Nm_per_rad", "ratio"}, {"torque_Nm", "rotation_rad", "ratio"}),
    "timing_belt": ({"ratio", "length_m", "tension_factor", "pulley_radius_m", "modulus_Pa", "section_m2", "width_m",
                     "tooth_factor_m3_per_N"},),
    "spring": ({"stiffness_Nm_per_rad", "ratio"}, {"stiffness_Nm_per_rad"}),
}


@dataclass(frozen=True)
class DriveComponentSpec:
    """One drive-train component as written in the case (units in the key names)."""

    kind: Literal["motor", "harmonic_reducer", "timing_belt", "spring"] = option(doc="component type")
    name: str = option("", doc="label")
    ratio: float | None = quantity("-", default=None, doc="speed reduction input/output")
    stiffness_Nm_per_rad: float | None = quantity("N m/rad", default=None)
    time_constant_s: float | None = quantity("s", default=None, doc="motor mechanical time constant t")
    rotor_inertia_kg_m2: float | None = quantity("kg m^2", default=None, doc="motor rotor inertia J_m")
    torque_Nm: float | None = quantity("N m", default=None, doc="reducer test torque T")
    rotation_rad: float | None = quantity("rad", default=None, doc="reducer output rotation phi under T")
    length_m: float | None = quantity("m", default=None, doc="belt length L")
    tension_factor: float | None = quantity("-", default=None, doc="belt tension factor a")
    pulley_radius_m: float | None = quantity("m", default=None, doc="driving pulley radius R")
    modulus_Pa: float | None = quantity("Pa", default=None, doc="belt modulus E")
    section_m2: float | None = quantity("m^2", default=None, doc="belt section between the teeth A")
    width_m: float | None = quantity("m", default=None, doc="belt width B")
    tooth_factor_m3_per_N: float | None = quantity("m^3/N", default=None, doc="tooth-form factor eta")

    def __post_init__(self):
        given = {f.name for f in dataclasses.fields(self) if f.name not in ("kind", "name") and getattr(self, f.name) is not None}
        options = _COMPONENT_FIELDS[self.kind]
        if not any(given == set(o) for o in options):
            wanted = " or ".join("{" + ", ".join(sorted(o)) + "}" for o in options)
            extra = sorted(given - set().union(*options))
            closest = min(options, key=lambda o: len(set(o) ^ given))
            missing = sorted(set(closest) - given)
            key = extra[0] if extra else (missing[0] if missing else "kind")
            raise ValueError(f"{key}: a {self.kind} needs exactly {wanted}; got {sorted(given)}")

    def component(self) -> dt.DriveComponent:
        """The spring this component adds (seed 003 eqs. 17, 19, 20)."""
        if self.kind == "motor":
            k = self.stiffness_Nm_per_rad if self.stiffness_Nm_per_rad is not None else dt.motor_stiffness(
                self.time_constant_s, self.rotor_inertia_kg_m2)
            return dt.DriveComponent(self.name or "motor", k, 1.0)
        if self.kind == "harmonic_reducer":
            k = self.stiffness_Nm_per_rad if self.stiffness_Nm_per_rad is not None else dt.reducer_stiffness(
                self.torque_Nm, self.rotation_rad)
            return dt.DriveComponent(self.name or "harmonic_reducer", k, self.ratio)
        if self.kind == "timing_belt":
            k = dt.timing_belt_stiffness(self.length_m, self.tension_factor, self.pulley_radius_m, self.modulus_Pa,
                                         self.section_m2, self.width_m, self.tooth_factor_m3_per_N)
            return dt.DriveComponent(self.name or "timing_belt", k, self.ratio)
        return dt.DriveComponent(self.name or "spring", self.stiffness_Nm_per_rad, self.ratio if self.ratio is not None else 1.0)


@dataclass(frozen=True)
class Joint:
    """One DH row and the joint's springs."""

    a_m: float = quantity("m", check="any", doc="standard: a_i; modified: a_{i-1}")
    alpha_deg: float = quantity("deg", check="any", doc="standard: alpha_i; modified: alpha_{i-1}")
    d_m: float = quantity("m", check="any")
    name: str = option("", doc="label")
    theta_offset_deg: float = quantity("deg", check="any", default=0.0, doc="theta_i = q_i + offset")
    stiffness_Nm_per_rad: float | None = quantity("N m/rad", default=None, doc="torsional joint stiffness (direct)")
    drive_train: tuple[DriveComponentSpec, ...] | None = option(None, doc="components from motor to output")
    tilt_stiffness_Nm_per_rad: tuple[float, float] | None = quantity("N m/rad", default=None,
                                                                     doc="extended VJM tilt springs about joint-frame x, y")
    tilt_offset_m: float = quantity("m", check="any", default=0.0, doc="tilt springs' place along the joint axis")
    mass_kg: float = quantity("kg", check="nonnegative", default=0.0, doc="link mass (self-weight diagnosis)")
    com_m: tuple[float, float, float] = quantity("m", check="any", default=(0.0, 0.0, 0.0), doc="link centre of mass in the DH frame")

    def __post_init__(self):
        if (self.stiffness_Nm_per_rad is None) == (self.drive_train is None):
            raise ValueError("stiffness_Nm_per_rad: give either stiffness_Nm_per_rad or [[joints.drive_train]] components, not both or neither")

    @property
    def torsional_stiffness(self) -> float:
        """N m/rad: direct, or the drive train's springs in series (seed 003 eq. 21)."""
        if self.stiffness_Nm_per_rad is not None:
            return self.stiffness_Nm_per_rad
        return dt.joint_stiffness([c.component() for c in self.drive_train])


@dataclass(frozen=True)
class Identification:
    """Measurement plan for the extended-VJM identification (seed 002 sec. IV)."""

    configurations_deg: tuple[tuple[float, ...], ...] = quantity("deg", check="any")
    wrenches: tuple[tuple[float, float, float, float, float, float], ...] = quantity("N, N m", check="any")
    rows: Literal["translation", "full"] = option("translation", doc="measured components")
    verification_configurations_deg: tuple[tuple[float, ...], ...] = quantity(
        "deg", check="any", default=(), doc="configurations that check the identified model (seed 002 Table I 9-13)")


@dataclass(frozen=True)
class SerialRobotCase(CaseRecord):
    """A validated serial-robot VJM case. Immutable."""

    model: ModelOptions
    kinematics: Kinematics
    joints: tuple[Joint, ...]
    identification: Identification | None = None
    gravity_m_per_s2: tuple[float, float, float] = (0.0, 0.0, -9.81)

    kind = CASE_KIND

    @property
    def n_joints(self) -> int:
        return len(self.joints)

    @property
    def chain(self) -> DHChain:
        j = self.joints
        return DHChain(a_m=tuple(x.a_m for x in j), alpha_rad=tuple(float(np.deg2rad(x.alpha_deg)) for x in j),
                       d_m=tuple(x.d_m for x in j), theta_offset_rad=tuple(float(np.deg2rad(x.theta_offset_deg)) for x in j),
                       convention=self.kinematics.convention, tool_offset_m=self.kinematics.tool_offset_m)

    @property
    def joint_stiffness(self) -> np.ndarray:
        """(n,) torsional joint stiffnesses, N m/rad."""
        return np.array([x.torsional_stiffness for x in self.joints])

    @property
    def virtual_stiffness(self) -> np.ndarray:
        """(n,) or (3n,) virtual-joint stiffnesses, N m/rad (order per joint: torsion, tilt x, tilt y)."""
        if self.model.vjm == "conventional":
            return self.joint_stiffness
        return np.array([[x.torsional_stiffness, *x.tilt_stiffness_Nm_per_rad] for x in self.joints]).ravel()

    def vjm(self, extended: bool | None = None) -> SerialVJM:
        """The VJM model; ``extended`` overrides ``model.vjm`` (False gives the conventional model of an extended case)."""
        ext = self.model.vjm == "extended" if extended is None else extended
        k = self.virtual_stiffness if ext else self.joint_stiffness
        return SerialVJM(chain=self.chain, k_theta=tuple(k), extended=ext,
                         tilt_offset_m=tuple(x.tilt_offset_m for x in self.joints) if ext else None)



def build(raw: dict, path) -> SerialRobotCase:
    """Validate a parsed TOML document into a :class:`SerialRobotCase` (errors name file and key)."""
    ctx = Context(path)
    parts = build_sections(ctx, raw,
                           {"meta": Meta, "model": ModelOptions, "kinematics": Kinematics},
                           optional=("meta", "model"), also_allowed=("joints", "identification", "gravity"))
    meta, model, kin = parts["meta"], parts["model"], parts["kinematics"]
    rows = raw.get("joints")
    if not isinstance(rows, list) or not rows:
        raise ctx.error("joints", "expected one or more [[joints]] tables (one per DH row)")
    joints = tuple(build_section(ctx, f"joints[{i}]", Joint, t) for i, t in enumerate(rows))
    if model.vjm == "extended":
        for i, j in enumerate(joints):
            if j.tilt_stiffness_Nm_per_rad is None:
                raise ctx.error(f"joints[{i}].tilt_stiffness_Nm_per_rad", "required when model.vjm = 'extended'")
    ident = None
    if "identification" in raw:
        ident = build_section(ctx, "identification", Identification, raw["identification"])
        for key in ("configurations_deg", "verification_configurations_deg"):
            for i, q in enumerate(getattr(ident, key)):
                if len(q) != len(joints):
                    raise ctx.error(f"identification.{key}[{i}]", f"has {len(q)} angles; expected {len(joints)}")
    from femcheck.case.serial_tree import Gravity
    grav = build_section(ctx, "gravity", Gravity, raw.get("gravity", {}))
    return SerialRobotCase(meta=meta, model=model, kinematics=kin, joints=joints, identification=ident,
                           gravity_m_per_s2=grav.vector_m_per_s2)
