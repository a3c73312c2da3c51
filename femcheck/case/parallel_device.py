"""A parallel device described leg by leg in the case file: hexapods, Delta-type robots, ...

TOML layout (SI; positions in the base frame at the *home pose*)::

    [meta]        kind = "parallel_device", name, reference
    [model]       joint_rotations = "rigid" | "released", beam_shear = false
    [materials.NAME]  E_Pa, nu, density_kg_m3
    [platform]    home_pose = [x, y, z, rx, ry, rz] (m, rad; rotation vector), tcp_offset_m = [0, 0, 0]
    [symmetry]    copies = N        every [[legs]] entry is repeated N times about the base z axis (360/N deg)
    [workspace]   nominal_tcp_m, cube_edge_m, corner_signs (8 sign triples), rotation = [rx, ry, rz]
    [loads]       test_N, directions; the two-level test protocol (optional): detailed_test_N, detailed_preload_N,
                  simplified_test_N, simplified_preload_N
    [actuation.fe], [measurement], [solid], [solver]   optional: the device FE's actuation model, the dial-gauge
                  protocol, the solid parts and the sparse solver (femcheck.case.device_options)
    [[legs]]      name, joints = [...]  (one table per joint, base to platform), links = [...]
        joints[k]  type = "R" | "U" | "S" | "P" | "F" (a clamp, first joint only), actuated, point_m (R/U/S: centre), axes (R: 1, U: 1 or 2, S: 3,
                   P: 1; optional for U, S, P), limits (R/P: range from home, rad or m), drive (actuated joint),
                   hertz_point (S), hertz_line (R/U), measured_law (S/U/R: a contact-FE compliance, file or inline)
        links[j]   the member between the j-th and (j+1)-th centred joint (R/U/S): element = "tube" | "bar" |
                   "rigid", material, outer/inner_diameter_m (tube), width_m/depth_m (bar), x_axis (section x)

Six ``F-P*-S-U`` legs in the paper's pairs with one set of parts are the 6-PSU layout: its tables are read from
the legs (:mod:`femcheck.case.psu_layout`; ``case.geometry``, ``case.guideway``, ...) and the case runs as
``case.kind == "haptic_6psu"`` (cases/haptic_6psu.toml).

A P joint has no centre: it sits inside the link between its neighbouring centred joints and slides along it (a
telescopic strut). The last joint's centre is the leg's platform attachment; the platform frame at
the home pose fixes where it is in the platform. The model is :mod:`femcheck.parallel`; the page
``docs/parallel_device.md`` is an annotated template.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Literal

import numpy as np

from femcheck.case.device_options import DeviceActuation, LawScale, LegScale, Measurement, ReadingEffects
from femcheck.case.haptic_6psu_solid import SolidModel
from femcheck.case.joint_contact_tables import HertzLine, HertzPoint
from femcheck.case.schema import (CaseMeta as Meta, CaseRecord, Context, Material, build_materials, build_section,
                                  build_sections, option, quantity)
from femcheck.case.solver_options import SolverOptions

CASE_KIND = "parallel_device"

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class ModelOptions:
    joint_rotations: Literal["rigid", "released"] = option(
        "released", doc="rigid: passive joints carry moments; released: ideal joints (free passive rotations)")
    beam_shear: bool = option(False, doc="add Timoshenko shear L/(kappa G A) to the lateral beam terms")
    element_scale: dict[str, tuple[float, ...]] | None = quantity(
        "-", check="nonnegative", default=None,
        doc="[model.element_scale]: per element kind (link names, drive, hertz_point, hertz_line, measured_law) one "
            "factor per leg (symmetry copies included) on its compliance; written by diagnose --extended-case")
    hertz_force: Literal["own_joint_force_at_test_load"] = option(
        "own_joint_force_at_test_load", doc="Hertz linearization force (docs/conventions.md §6)")
    law_scale: LawScale = LawScale()
    leg_scale: LegScale = LegScale()
    joint_rotation_compliance_rad_per_Nm: float = quantity(
        "rad/(N m)", check="nonnegative", default=0.0,
        doc="compliance of every passive S/U joint rotation for rigid joints (joint_rotation_release; 0 = rigid)")
    reading: ReadingEffects = ReadingEffects()

    def __post_init__(self):
        # held as sorted (kind, factors) pairs: the case is frozen and hashed (the resolved device is cached per case)
        if isinstance(self.element_scale, dict):
            object.__setattr__(self, "element_scale", tuple(sorted(self.element_scale.items())))


@dataclass(frozen=True)
class Platform:
    home_pose: tuple[float, float, float, float, float, float] = quantity(
        "m, rad", check="any", doc="platform frame at the home pose (the joint points are given there)")
    tcp_offset_m: Vec3 = quantity("m", check="any", default=(0.0, 0.0, 0.0), doc="TCP in the platform frame")


@dataclass(frozen=True)
class Symmetry:
    copies: int = quantity("-", default=1, doc="rotational copies of the listed legs about the base z axis")


@dataclass(frozen=True)
class Workspace:
    nominal_tcp_m: Vec3 = quantity("m", check="any", doc="P0, centre of the test cube")
    cube_edge_m: float = quantity("m", doc="edge of the test cube")
    corner_signs: tuple[tuple[int, int, int], ...] = quantity(
        "-", check="any", default=((-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1),
                                   (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)), doc="P1..P8 sign triples")
    rotation: Vec3 = quantity("rad", check="any", default=(0.0, 0.0, 0.0), doc="platform rotation vector at every test point")

    def __post_init__(self):
        if len(self.corner_signs) != 8 or any(abs(s) != 1 for row in self.corner_signs for s in row):
            raise ValueError("corner_signs: expected 8 triples of +-1")


@dataclass(frozen=True)
class Loads:
    """The test loads at the TCP. The test protocol of a two-level campaign (the 6-PSU's, seed 000 §4.7): a
    simplified experiment (preload, then preload + test force) and a detailed one; ``test_N`` is the detailed
    test force where the file gives only that (and 10 N where it gives neither)."""
    test_N: float | None = quantity("N", default=None, doc="TCP test force (the Hertz contacts are linearized at it)")
    directions: tuple[str, ...] = option(("+x", "-x", "+y", "-y", "+z", "-z"), doc="TCP load directions")
    detailed_test_N: float | None = quantity("N", default=None, doc="detailed experiment's test force (default test_N)")
    detailed_preload_N: float = quantity("N", check="nonnegative", default=0.0, doc="detailed experiment's preload")
    simplified_test_N: float | None = quantity("N", default=None,
                                               doc="simplified experiment's test force (default detailed_test_N)")
    simplified_preload_N: float = quantity("N", check="nonnegative", default=0.0, doc="simplified experiment's preload")

    def __post_init__(self):
        test = self.test_N if self.test_N is not None else (self.detailed_test_N or 10.0)
        object.__setattr__(self, "test_N", test)
        if self.detailed_test_N is None:
            object.__setattr__(self, "detailed_test_N", test)
        if self.simplified_test_N is None:
            object.__setattr__(self, "simplified_test_N", self.detailed_test_N)
        bad = [d for d in self.directions if d not in ("+x", "-x", "+y", "-y", "+z", "-z")]
        if bad:
            raise ValueError(f"directions: {bad[0]!r} is not one of +x, -x, +y, -y, +z, -z")


@dataclass(frozen=True)
class Drive:
    """Drive train of the actuated joint: a spring along the P axis (``axial``) or about the R axis (``torsional``).

    Either ``stiffness`` (N/m or N m/rad) directly, or its ingredients (``femcheck.compliance.actuation``):
    axial = cable (E A / l) in series with the motor shaft torsion seen through the capstan; torsional =
    shaft torsion G J / L times ``gear_ratio``^2 (gearbox taken rigid).
    """
    law: Literal["axial", "torsional"] = option(doc="axial (P joint) or torsional (R joint)")
    stiffness: float | None = quantity("N/m | N m/rad", default=None)
    cable_diameter_m: float | None = quantity("m", default=None)
    cable_modulus_Pa: float | None = quantity("Pa", default=None)
    cable_length_m: float | None = quantity("m", default=None)
    shaft_diameter_m: float | None = quantity("m", default=None)
    shaft_length_m: float | None = quantity("m", default=None)
    shaft_G_Pa: float | None = quantity("Pa", default=None)
    capstan_radius_m: float | None = quantity("m", default=None)
    gear_ratio: float = quantity("-", default=1.0)

    def __post_init__(self):
        if self.stiffness is not None:
            return
        shaft = ("shaft_diameter_m", "shaft_length_m", "shaft_G_Pa")
        need = shaft + (("cable_diameter_m", "cable_modulus_Pa", "cable_length_m", "capstan_radius_m")
                        if self.law == "axial" else ())
        missing = [k for k in need if getattr(self, k) is None]
        if missing:
            raise ValueError(f"{missing[0]}: required for a {self.law} drive without 'stiffness'")

    @property
    def compliance(self) -> float:
        """Drive compliance: m/N (axial) or rad/(N m) (torsional)."""
        if self.stiffness is not None:
            return 1.0 / self.stiffness
        from femcheck.compliance.actuation import cable_stiffness, motor_stiffness_at_cable
        if self.law == "axial":
            k_c = cable_stiffness(self.cable_modulus_Pa, self.cable_diameter_m, self.cable_length_m)
            k_m = motor_stiffness_at_cable(self.shaft_G_Pa, self.shaft_diameter_m, self.shaft_length_m,
                                           self.capstan_radius_m)
            return float(1.0 / k_c + 1.0 / (k_m * self.gear_ratio**2))
        K_rotor = motor_stiffness_at_cable(self.shaft_G_Pa, self.shaft_diameter_m, self.shaft_length_m, 1.0)
        return float(1.0 / (K_rotor * self.gear_ratio**2))


@dataclass(frozen=True)
class MeasuredLaw:
    """A joint's compliance measured by the joint contact FE (``femcheck check-joints --json``): the constant 6 x 6
    ``fe_compliance`` (SI: m/N, m/(N m), rad/(N m)) at the joint centre, in the joint frame x, y lateral, z axial
    (the adjacent link's axis), rotations theta_x, theta_y (tilt / pin axes), theta_z (spin).

    Give ``file`` (a ``check-joints`` JSON, a list of results or one object with ``fe_compliance``; a relative path
    resolves against the case file's directory; ``joint`` picks the entry of a list with several) or ``compliance``
    inline. When the case loads, a file is read and inlined (``compliance`` and ``source``, the resolved path), so
    the case's document, its hash and its variants carry the measured numbers. ``frame``: the link whose frame is the
    joint frame (default: the link before the joint, the one after it for the first joint, as ``hertz_line``).

    A force ladder (``loads_N`` with ``approach_m``, as :class:`femcheck.fe_device.joint_laws.MeasuredJointLaw`; in
    the file or inline) makes the axial entry load-dependent: the tangent ``d delta / dF`` of the piecewise power
    law through the ladder, at the joint's own axial force (fixed point, as ``hertz_point``). A ``check-joints``
    file's ``loads_N`` without ``approach_m`` are its two eq. 1 levels, not a ladder, and are not read."""
    file: str | None = option(None, doc="check-joints JSON with fe_compliance (relative to the case file)")
    joint: Literal["spherical", "universal"] | None = option(None, doc="entry of a multi-joint check-joints JSON")
    compliance: tuple[tuple[float, ...], ...] | None = quantity("m/N, m/(N m), rad/(N m)", check="any", default=None,
                                                               doc="6 x 6 compliance in the joint frame (inline)")
    frame: Literal["link_before", "link_after"] | None = option(None, doc="link whose frame is the joint frame")
    source: str = option("", doc="where the numbers come from (set to the resolved file when a file is inlined)")
    loads_N: tuple[float, ...] | None = quantity("N", default=None, doc="force ladder (with approach_m, inline)")
    approach_m: tuple[float, ...] | None = quantity("m", default=None, doc="joint approach at each ladder force")

    def __post_init__(self):
        if (self.file is None) == (self.compliance is None):
            raise ValueError("file: give exactly one of file (a check-joints JSON) or compliance (6 x 6 inline)")
        if self.file is not None and (self.loads_N is not None or self.approach_m is not None):
            raise ValueError("loads_N: a ladder goes with an inline compliance; a file brings its own")
        _check_ladder(self.loads_N, self.approach_m)


def _check_ladder(F, d) -> None:
    """A force ladder: both or neither; >= 2 increasing positive forces, approach positive and growing with them."""
    if F is None and d is None:
        return
    if F is None or d is None:
        raise ValueError(f"{'loads_N' if F is None else 'approach_m'}: a ladder needs both loads_N and approach_m")
    F, d = np.asarray(F, float), np.asarray(d, float)
    if F.ndim != 1 or F.size < 2 or np.any(np.diff(F) <= 0):
        raise ValueError("loads_N: expected >= 2 increasing positive forces")
    if d.shape != F.shape or np.any(d <= 0) or np.any(np.diff(d) <= 0):
        raise ValueError("approach_m: expected one positive approach per force, growing with the force")


@dataclass(frozen=True)
class JointSpec:
    type: Literal["R", "U", "S", "P", "F"] = option(
        doc="revolute, universal, spherical, prismatic; F: a fixed clamp (only first: the leg starts with a clamped link)")
    actuated: bool = option(False, doc="the driven joint of the leg (R or P)")
    point_m: Vec3 | None = quantity("m", check="any", default=None, doc="centre at the home pose (R, U, S)")
    axes: tuple[Vec3, ...] | None = quantity("-", check="any", default=None, doc="joint axes at the home pose")
    limits: tuple[float, float] | None = quantity("m | rad", check="any", default=None,
                                                  doc="range of an R or P joint, from its home value (reach check)")
    drive: Drive | None = option(None)
    hertz_point: HertzPoint | None = option(None)
    hertz_line: HertzLine | None = option(None)
    measured_law: MeasuredLaw | None = option(None)

    def __post_init__(self):
        if self.type == "P" and self.point_m is not None:
            raise ValueError("point_m: a P joint has no centre; it slides inside the link between its neighbours")
        if self.type != "P" and self.point_m is None:
            raise ValueError(f"point_m: required for a {self.type} joint (its centre at the home pose)")
        if self.actuated and self.type not in ("R", "P"):
            raise ValueError(f"actuated: a {self.type} joint cannot be actuated; expected R or P")
        if self.actuated and self.drive is None:
            raise ValueError("drive: required for the actuated joint")
        if self.drive is not None and not self.actuated:
            raise ValueError("drive: only the actuated joint has a drive")
        if self.drive is not None and self.drive.law != {"P": "axial", "R": "torsional"}[self.type]:
            raise ValueError(f"drive.law: {self.drive.law!r} does not fit a {self.type} joint")
        if self.limits is not None and (self.type not in ("R", "P") or not self.limits[0] < self.limits[1]):
            raise ValueError("limits: only for an R or P joint, as [low, high] from its home value (low < high)")
        if self.hertz_point is not None and self.type != "S":
            raise ValueError("hertz_point: only on an S joint")
        if self.hertz_line is not None and self.type not in ("R", "U"):
            raise ValueError("hertz_line: only on an R or U joint")
        if self.measured_law is not None and self.type not in ("R", "U", "S"):
            raise ValueError("measured_law: only on an R, U or S joint")
        n_axes = {"R": (1,), "U": (1, 2), "S": (3,), "P": (1,), "F": (0,)}[self.type]
        if self.axes is not None and len(self.axes) not in n_axes:
            raise ValueError(f"axes: {len(self.axes)} given; a {self.type} joint takes {' or '.join(map(str, n_axes))}")
        if self.type == "R" and self.axes is None:
            raise ValueError("axes: required for an R joint (its axis at the home pose)")
        if self.axes is not None:
            A = np.asarray(self.axes, dtype=float)
            if np.any(np.linalg.norm(A, axis=1) < 1e-12):
                raise ValueError("axes: contains a zero vector")
            A = A / np.linalg.norm(A, axis=1, keepdims=True)
            if len(A) > 1 and np.abs(A @ A.T - np.eye(len(A))).max() > 1e-6:
                raise ValueError("axes: the axes of one joint must be mutually orthogonal")


@dataclass(frozen=True)
class LinkSpec:
    element: Literal["tube", "bar", "rigid"] = option(doc="cantilever tube (round), cantilever bar (rectangle) or rigid")
    name: str = option("link", doc="element name in contributions (e.g. strut, crank, rod)")
    material: Material | None = option(None)
    outer_diameter_m: float | None = quantity("m", default=None)
    inner_diameter_m: float = quantity("m", check="nonnegative", default=0.0)
    width_m: float | None = quantity("m", default=None, doc="bar, along the section x axis")
    depth_m: float | None = quantity("m", default=None, doc="bar, along the section y axis")
    x_axis: Vec3 | None = quantity("-", check="any", default=None,
                                   doc="section x axis at the home pose (default: normal to the link, horizontal)")

    def __post_init__(self):
        if self.element != "rigid" and self.material is None:
            raise ValueError(f"material: required for a {self.element} link")
        if self.element == "tube":
            if self.outer_diameter_m is None:
                raise ValueError("outer_diameter_m: required for a tube")
            if self.inner_diameter_m >= self.outer_diameter_m:
                raise ValueError(f"inner_diameter_m: = {self.inner_diameter_m}; expected < outer_diameter_m")
        if self.element == "bar" and (self.width_m is None or self.depth_m is None):
            raise ValueError("width_m: a bar needs width_m and depth_m")


@dataclass(frozen=True)
class LegSpec:
    joints: tuple[JointSpec, ...] = option(doc="base to platform")
    links: tuple[LinkSpec, ...] = option(doc="one per pair of consecutive centred joints")
    name: str = option("leg")


@dataclass(frozen=True)
class ParallelDeviceCase(CaseRecord):
    """A validated parallel device case. Immutable; the resolved legs are :attr:`device`."""

    model: ModelOptions
    materials: tuple[Material, ...]
    platform: Platform
    symmetry: Symmetry
    workspace: Workspace
    loads: Loads
    legs: tuple[LegSpec, ...]
    #: ``[actuation]``: the device FE's actuation model (the drives are the legs')
    actuation_options: DeviceActuation = DeviceActuation()
    #: ``[measurement]``: the dial-gauge protocol of a simulated or measured campaign (None: not stated)
    measurement: Measurement | None = None
    #: ``[solid]``: the solid (FE) parts of a 6-PSU layout (docs/fe_solver.md)
    solid: SolidModel = SolidModel()
    solver: SolverOptions = SolverOptions()

    @property
    def kind(self) -> str:
        """The model the case runs on: ``"haptic_6psu"`` where the legs are the 6-PSU layout
        (:mod:`femcheck.case.psu_layout`: its chain model, device FE, coverage and diagnosis), else
        ``"parallel_device"``. The file's ``[meta] kind`` is ``"parallel_device"`` for both."""
        return "haptic_6psu" if self.layout is not None else CASE_KIND

    @property
    def layout(self):
        """The 6-PSU tables read from the legs (:class:`~femcheck.case.psu_layout.PSULayout`), or None."""
        from femcheck.case.psu_layout import psu_layout
        return psu_layout(self)

    def expand_params(self, raw: dict, dotted: dict[str, object]) -> dict[str, object]:
        """Dotted keys of the derived 6-PSU tables (``"guideway.width_radial_m"``) written into ``raw``'s legs; the
        keys left to set as they are returned (:func:`femcheck.case.registry.with_params`)."""
        if self.layout is None:
            return dotted
        from femcheck.case.psu_layout import with_layout_params
        return with_layout_params(self, raw, dotted)

    def _table(self, name: str):
        lay = self.layout
        if lay is None:
            raise AttributeError(f"{name}: only a 6-PSU layout has this table (femcheck.case.psu_layout)")
        return getattr(lay, name)

    # the paper's tables of a 6-PSU layout, read from the legs once (femcheck.case.psu_layout)
    geometry = property(lambda self: self._table("geometry"))
    guideway = property(lambda self: self._table("guideway"))
    proximal_link = property(lambda self: self._table("proximal_link"))
    spherical_joint = property(lambda self: self._table("spherical_joint"))
    universal_joint = property(lambda self: self._table("universal_joint"))
    base_points = property(lambda self: self._table("base_points"), doc="(6, 3) clamp points A_i, m")
    platform_points = property(lambda self: self._table("platform_points"), doc="(6, 3) C_i, platform frame, m")
    base_angles_rad = property(lambda self: self._table("base_angles_rad"))
    platform_angles_rad = property(lambda self: self._table("platform_angles_rad"))

    @property
    def actuation(self):
        """The 6-PSU's actuation table (every leg's drive and ``[actuation.fe]``) or, for another device, the
        ``[actuation]`` section."""
        lay = self.layout
        return lay.actuation if lay is not None else self.actuation_options

    @property
    def n_chains(self) -> int:
        return self.n_legs

    def material(self, name: str) -> Material:
        for m in self.materials:
            if m.name == name:
                return m
        raise KeyError(name)

    @property
    def device(self):
        """The legs resolved into arrays (:class:`femcheck.parallel.device.ParallelDevice`), cached per case."""
        return _device(self)

    @property
    def n_legs(self) -> int:
        return len(self.legs) * self.symmetry.copies


def _device(case):
    from femcheck.compliance.kernel_laws import law_functions
    return _device_for(case, law_functions())


@functools.lru_cache(maxsize=32)
def _device_for(case, laws):
    """The device of ``case`` with the law functions ``laws`` (cached per case and laws: a law replaced in its
    module builds the device again)."""
    from femcheck.parallel.device import device_from_case
    return device_from_case(case)


SECTIONS = {"meta": Meta, "model": ModelOptions, "platform": Platform, "symmetry": Symmetry,
            "workspace": Workspace, "loads": Loads, "actuation": DeviceActuation, "solid": SolidModel,
            "solver": SolverOptions}


def _check_leg(ctx: Context, i: int, leg: LegSpec) -> None:
    """Cross-joint checks of one leg; the error names the leg (its index in the file and its name)."""
    where = f"legs[{i}]"
    who = f"leg {i} ({leg.name!r})"
    j = leg.joints
    if len(j) < 2:
        raise ctx.error(f"{where}.joints", f"{who} has {len(j)} joint(s); expected at least 2 (base and platform)")
    if j[0].type == "P" or j[-1].type in ("P", "F"):
        raise ctx.error(f"{where}.joints", f"{who}: the first and last joints must have a centre (R, U or S; F first), "
                                           f"not {j[0].type if j[0].type == 'P' else j[-1].type}")
    if any(jt.type == "F" for jt in j[1:]):
        raise ctx.error(f"{where}.joints", f"{who}: an F (clamp) joint can only be the first joint")
    act = [k for k, jt in enumerate(j) if jt.actuated]
    if len(act) != 1:
        raise ctx.error(f"{where}.joints", f"{who} has {len(act)} actuated joints; expected exactly one")
    for k in range(1, len(j)):
        if j[k].type == "P" and j[k - 1].type == "P":
            raise ctx.error(f"{where}.joints[{k}]", f"{who}: two P joints in one link")
    centred = [jt for jt in j if jt.type != "P"]
    if len(leg.links) != len(centred) - 1:
        raise ctx.error(f"{where}.links", f"{who} has {len(leg.links)} links; expected {len(centred) - 1} "
                                          f"(one between each pair of consecutive R/U/S joints)")
    pts = np.array([jt.point_m for jt in centred], dtype=float)
    lengths = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    if np.any(lengths < 1e-9):
        k = int(np.argmin(lengths))
        raise ctx.error(f"{where}.links[{k}]", f"{who}: link {k} has zero length at the home pose")
    dof = sum({"R": 1, "U": 2, "S": 3, "P": 1, "F": 0}[jt.type] for jt in j)
    if dof < 3:
        raise ctx.error(f"{where}.joints", f"{who} has {dof} joint freedoms; a leg needs at least 3")


def _law_from_file(ctx: Context, key: str, who: str, law: MeasuredLaw):
    """(6, 6) ``fe_compliance`` of the check-joints JSON ``law.file`` (resolved against the case file's directory)
    and the resolved path; a one-line error naming the leg, joint and key otherwise."""
    import json
    from pathlib import Path
    base = Path(str(ctx.path)).parent if ctx.path is not None else Path(".")
    path = Path(law.file).expanduser()
    path = path if path.is_absolute() else base / path
    if not path.is_file():
        raise ctx.error(f"{key}.file", f"{who}: joint law file {str(path)!r} not found")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ctx.error(f"{key}.file", f"{who}: {str(path)!r} is not a JSON file ({exc})") from None
    entries = doc if isinstance(doc, list) else [doc]
    entries = [e for e in entries if isinstance(e, dict) and "fe_compliance" in e]
    if law.joint is not None:
        entries = [e for e in entries if e.get("joint") == law.joint]
    if len(entries) != 1:
        what = (f"no entry with fe_compliance{f' for joint {law.joint!r}' if law.joint else ''}" if not entries else
                f"{len(entries)} entries with fe_compliance; pick one with joint = \"spherical\" | \"universal\"")
        raise ctx.error(f"{key}.joint" if entries else f"{key}.file", f"{who}: {str(path)!r} has {what} "
                        "(expected the JSON of femcheck check-joints --json)")
    e = entries[0]
    ladder = (e.get("loads_N"), e.get("approach_m")) if "approach_m" in e else (None, None)
    return e["fe_compliance"], ladder, str(path.resolve())


def _law_matrix(ctx: Context, key: str, who: str, value) -> np.ndarray:
    """The 6 x 6 compliance ``value`` checked: finite, symmetric (to 1e-6 of its largest entry), positive definite."""
    try:
        S = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ctx.error(key, f"{who}: the compliance is not a 6 x 6 matrix of numbers "
                             "(null entries, a mechanism, are not accepted)") from None
    if S.shape != (6, 6):
        raise ctx.error(key, f"{who}: the compliance has shape {S.shape}; expected 6 x 6 (SI, joint frame)")
    if not np.all(np.isfinite(S)):
        raise ctx.error(key, f"{who}: the compliance has entries that are not finite")
    scale = np.abs(S).max()
    if scale == 0.0 or np.abs(S - S.T).max() > 1e-6 * scale:
        raise ctx.error(key, f"{who}: the compliance is not symmetric (max |S - S^T| = {np.abs(S - S.T).max():.3g}, "
                             f"largest entry {scale:.3g})")
    S = 0.5 * (S + S.T)
    d = np.diag(S)
    # positive definite: the diagonal, then the unit-free correlation matrix (entries mix m/N and rad/(N m))
    ok = bool(np.all(d > 0))
    if ok:
        D = 1.0 / np.sqrt(d)
        ok = bool(np.linalg.eigvalsh(D[:, None] * S * D[None, :]).min() > 1e-12)
    if not ok:
        raise ctx.error(key, f"{who}: the compliance is not positive definite")
    return S


def _with_measured_laws(ctx: Context, i: int, leg: LegSpec, leg_raw: dict) -> LegSpec:
    """Read and check every ``measured_law`` of leg ``i``; a file is inlined into the leg and into ``leg_raw`` (the
    case document, so its hash and its variants carry the numbers: :class:`MeasuredLaw`)."""
    import dataclasses
    joints = list(leg.joints)
    centred = [k for k, jt in enumerate(joints) if jt.type != "P"]
    for k, jt in enumerate(joints):
        law = jt.measured_law
        if law is None:
            continue
        key = f"legs[{i}].joints[{k}].measured_law"
        who = f"leg {i} ({leg.name!r}), joint {k} ({jt.type})"
        c = centred.index(k)
        if law.frame == "link_before" and c == 0:
            raise ctx.error(f"{key}.frame", f"{who}: the first joint has no link before it; use link_after")
        if law.frame == "link_after" and c == len(centred) - 1:
            raise ctx.error(f"{key}.frame", f"{who}: the last joint has no link after it; use link_before")
        if law.file is not None:
            value, (F, d), source = _law_from_file(ctx, key, who, law)
            S = _law_matrix(ctx, f"{key}.file", who, value)
            try:
                _check_ladder(F, d)
                F = None if F is None else tuple(float(v) for v in F)
                d = None if d is None else tuple(float(v) for v in d)
            except (ValueError, TypeError) as exc:
                raise ctx.error(f"{key}.file", f"{who}: {source!r}: {exc}") from None
            law = dataclasses.replace(law, file=None, joint=None, source=source, loads_N=F, approach_m=d,
                                      compliance=tuple(tuple(float(v) for v in row) for row in S))
            inline = {"compliance": [list(r) for r in law.compliance], "source": source}
            if F is not None:
                inline.update(loads_N=list(F), approach_m=list(d))
            if law.frame is not None:
                inline["frame"] = law.frame
            leg_raw["joints"][k]["measured_law"] = inline
        else:
            _law_matrix(ctx, f"{key}.compliance", who, law.compliance)
        joints[k] = dataclasses.replace(jt, measured_law=law)
    return dataclasses.replace(leg, joints=tuple(joints))


def build(raw: dict, path) -> ParallelDeviceCase:
    """Validate a parsed TOML document into a :class:`ParallelDeviceCase` (errors name the file, key and leg).
    A ``measured_law`` file is read here and inlined into ``raw`` (:class:`MeasuredLaw`)."""
    ctx = Context(path)
    ctx.materials = build_materials(ctx, raw.get("materials"))
    parts = build_sections(ctx, raw, SECTIONS, optional=("meta", "model", "symmetry", "loads", "actuation", "solid",
                                                         "solver"),
                           also_allowed=("materials", "legs", "measurement"))
    parts["actuation_options"] = parts.pop("actuation")
    if "measurement" in raw:
        parts["measurement"] = build_section(ctx, "measurement", Measurement, raw["measurement"])
    legs_raw = raw.get("legs")
    if not isinstance(legs_raw, list) or not legs_raw:
        raise ctx.error("legs", "expected at least one [[legs]] table")
    legs = tuple(build_section(ctx, f"legs[{i}]", LegSpec, t) for i, t in enumerate(legs_raw))
    for i, leg in enumerate(legs):
        _check_leg(ctx, i, leg)
    legs = tuple(_with_measured_laws(ctx, i, leg, legs_raw[i]) for i, leg in enumerate(legs))
    case = ParallelDeviceCase(materials=tuple(ctx.materials.values()), legs=legs, **parts)
    # resolve the legs once: the home configuration must close (platform attachment consistent) and every
    # test point be reachable; the error names the first leg that is not
    from femcheck.parallel.device import DeviceError, device_from_case
    try:
        # a 6-PSU layout is checked pose by pose by its inverse kinematics (an unreachable pose is named where it is
        # evaluated; a sweep marks it), so that a variant of its tables (a shorter rail, say) still loads
        device_from_case(case, check_points=case.layout is None)
    except DeviceError as exc:
        raise ctx.error(exc.key, str(exc)) from None
    return case
