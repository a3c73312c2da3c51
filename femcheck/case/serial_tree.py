"""The serial-tree case: a robot whose kinematics is a tree of revolute and prismatic DH rows, with link masses,
gravity, markers, nominal joint springs, and the options of the self-weight diagnosis.

TOML layout (SI; angles only in keys ending ``_deg``; docs/diagnose.md has an annotated template)::

    [meta]            kind = "serial_tree", name, reference
    [kinematics]      convention = "standard" | "modified"  (stated once for every row)
    [gravity]         vector_m_per_s2 = [0, 0, -9.81]  in the robot's base frame
    [[joints]]        one table per DH row, in the order of the CSV's q1..qN columns (coupled rows excepted):
                      name, type ("revolute", default, or "prismatic"), parent ("base" or an earlier row's name; default: the row before), branch (label
                      used to name places, default: the parent's branch, or "main"), a_m, alpha_deg, d_m,
                      theta_offset_deg; a static frame before the row: static_origin_m, static_rpy_deg (in the
                      parent's frame); coupling = {row = c, ...} for a passive row (q = sum c q_row, no CSV
                      column); mass_kg and com_m (the link carried by the row, in its frame); nominal springs:
                      stiffness_Nm_per_rad (torsion; absent = rigid; on a coupled row: the row's own spring, in
                      series with its coupling, whose torque still reaches the driving rows by virtual work), tilt_stiffness_Nm_per_rad = [kx, ky],
                      bending_EI_Nm2 (link after the row); size (a label that lumps joints of one size);
                      backlash_rad, backlash_torque_Nm (gear clearance of an independent row and its take-up torque)
                      prismatic rows: q (m) adds to d_m (the slide along the row's z), theta_offset_deg is the
                      fixed theta; axial_stiffness_N_per_m (nominal axial spring of the drive; absent = rigid)
                      instead of stiffness_Nm_per_rad; tilt_stiffness_Nm_per_rad: the moving stage's tilt springs
                      at the carriage; guide_overlap_m (the length over which the stage's guide engages at q = 0;
                      it shrinks as q grows: L(q) = guide_overlap_m - q; needed for the guide_clearance cause);
                      guide_clearance_m (nominal diametral clearance of the guide; absent = none)
    [[markers]]       name, link (row name), offset_m (nominal, in the row's frame)
    [payload]         optional: link, com_m -- where the CSV's payload_kg hangs
    [sensor_frame]    optional: rotation_vector_rad, translation_m -- sensor <- base (a corrected case holds it)
    [measurement]     sigma_m (per-coordinate noise of a marker position, optional), folds
    [diagnosis]       fixed_point_passes, prior sigmas of the nuisance parameters (see ``DiagnosisOptions``)

Prismatic rows (frames as above with theta fixed and d = d_m + q): the row's *joint frame* is the carriage,
``parent * S Rz(theta) Tz(d)`` (standard) or ``parent * S Rx(alpha) Tx(a) Rz(theta) Tz(d)`` (modified); the stage's
tilt springs and its guide play turn the rest of the row about the carriage. The CSV column of a prismatic
joint is ``qK_m`` (metres) instead of ``qK_rad``. A coupled row may follow prismatic rows (``coupling`` ratios then
in rad/m or m/m).

Frames. Standard DH: ``T_row = S Rz(theta) Tz(d) Tx(a) Rx(alpha)``, the joint turns about the z axis of
``parent * S``; modified (Craig): ``T_row = S Rx(alpha) Tx(a) Rz(theta) Tz(d)``, the joint turns about the
row's own z. ``S`` is the static frame (origin, then roll-pitch-yaw about fixed x, y, z). The row's frame
carries its link's centre of mass, its markers, and its children.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from femcheck.case.schema import CaseMeta as Meta, CaseRecord, Context, build_section, build_sections, option, quantity

CASE_KIND = "serial_tree"


@dataclass(frozen=True)
class TreeKinematics:
    convention: Literal["standard", "modified"] = option(doc="DH convention of every row: standard or modified (Craig)")


@dataclass(frozen=True)
class Gravity:
    vector_m_per_s2: tuple[float, float, float] = quantity("m/s^2", check="any", default=(0.0, 0.0, -9.81),
                                                           doc="gravity in the base frame")


@dataclass(frozen=True)
class TreeJoint:
    """One DH row of the tree and what it carries."""

    name: str = option(doc="row name (unique); markers, payload and children refer to it")
    a_m: float = quantity("m", check="any")
    alpha_deg: float = quantity("deg", check="any")
    d_m: float = quantity("m", check="any")
    theta_offset_deg: float = quantity("deg", check="any", default=0.0, doc="theta = q + offset")
    type: Literal["revolute", "prismatic"] = option("revolute", doc="revolute (q turns theta) or prismatic (q slides d)")
    parent: str = option("", doc="'base' or an earlier row; default: the row before")
    branch: str = option("", doc="label of the branch (e.g. 'right_arm'); default: the parent's, or 'main'")
    size: str = option("", doc="label lumping joints of one size (causes may be fitted per size)")
    static_origin_m: tuple[float, float, float] = quantity("m", check="any", default=(0.0, 0.0, 0.0),
                                                           doc="static frame before the row: origin in the parent's frame")
    static_rpy_deg: tuple[float, float, float] = quantity("deg", check="any", default=(0.0, 0.0, 0.0),
                                                          doc="static frame: roll, pitch, yaw about fixed x, y, z")
    coupling: dict[str, float] | None = option(None, doc="passive row: q = sum_j c_j q_j over the named rows")
    mass_kg: float = quantity("kg", check="nonnegative", default=0.0)
    com_m: tuple[float, float, float] = quantity("m", check="any", default=(0.0, 0.0, 0.0), doc="centre of mass in the row's frame")
    stiffness_Nm_per_rad: float | None = quantity("N m/rad", default=None,
                                                  doc="nominal torsion spring (a coupled row: its own, in series with the coupling); absent = rigid")
    tilt_stiffness_Nm_per_rad: tuple[float, float] | None = quantity("N m/rad", default=None,
                                                                     doc="nominal tilt springs about joint-frame x, y")
    bending_EI_Nm2: float | None = quantity("N m^2", default=None, doc="nominal bending stiffness of the row's link")
    backlash_rad: float | None = quantity("rad", check="nonnegative", default=None,
                                          doc="gear clearance of an independent joint: dq = b tanh(tau / tau_s); absent = none")
    backlash_torque_Nm: float | None = quantity("N m", default=None,
                                                doc="tau_s, torque over which the backlash takes up (default: the diagnosis')")
    axial_stiffness_N_per_m: float | None = quantity("N/m", default=None,
                                                     doc="prismatic rows: nominal axial spring of the drive; absent = rigid")
    guide_overlap_m: float | None = quantity("m", default=None,
                                             doc="prismatic rows: guide engagement length at q = 0; L(q) = guide_overlap_m - q")
    guide_clearance_m: float | None = quantity("m", check="nonnegative", default=None,
                                               doc="prismatic rows: nominal diametral clearance of the guide")


@dataclass(frozen=True)
class Marker:
    name: str = option(doc="marker name used in the CSV's marker column")
    link: str = option(doc="row whose frame carries the marker")
    offset_m: tuple[float, float, float] = quantity("m", check="any", default=(0.0, 0.0, 0.0), doc="nominal offset in that frame")


@dataclass(frozen=True)
class Payload:
    link: str = option(doc="row whose frame carries the payload of the CSV's payload_kg column")
    com_m: tuple[float, float, float] = quantity("m", check="any", default=(0.0, 0.0, 0.0))


@dataclass(frozen=True)
class Measurement:
    sigma_m: float | None = quantity("m", default=None, doc="noise of one coordinate of a marker position (1 sigma)")
    folds: int = quantity("-", default=5, doc="K of the K-fold cross-validation over poses (CSV fold column wins)")


@dataclass(frozen=True)
class SensorFrame:
    """Where the measuring system sees the base: x_sensor = R(rotation_vector_rad) p_base + translation_m. A
    corrected case (``diagnose --extended-case``) holds the calibrated frame, so that it predicts the readings; the
    diagnosis itself always calibrates the frame afresh."""

    rotation_vector_rad: tuple[float, float, float] = quantity("rad", check="any", default=(0.0, 0.0, 0.0),
                                                               doc="sensor <- base rotation (rotation vector)")
    translation_m: tuple[float, float, float] = quantity("m", check="any", default=(0.0, 0.0, 0.0),
                                                         doc="base origin in the sensor frame")


@dataclass(frozen=True)
class DiagnosisOptions:
    """Options of the self-weight diagnosis; the prior sigmas are the stated weak Gaussian prior of the nuisance
    parameters around their nominal values."""

    fixed_point_passes: int = quantity("-", default=2, doc="passes of the torque equilibrium at the deflected configuration")
    prior_length_m: float = quantity("m", default=0.01, doc="prior sigma of d, a and static-frame offsets")
    prior_angle_deg: float = quantity("deg", default=2.0, doc="prior sigma of theta offsets, alpha and static-frame angles")
    prior_marker_m: float = quantity("m", default=0.05, doc="prior sigma of each marker offset coordinate")
    backlash_torque_Nm: float | None = quantity("N m", default=None,
                                                doc="torque over which backlash takes up (tanh width); default 5 % of each joint's median |tau|")


@dataclass(frozen=True)
class SerialTreeCase(CaseRecord):
    """A validated serial-tree case. Immutable; ``tree`` is the array form used by every computation."""

    kinematics: TreeKinematics
    gravity: Gravity
    joints: tuple[TreeJoint, ...]
    markers: tuple[Marker, ...]
    payload: Payload | None
    measurement: Measurement
    diagnosis: DiagnosisOptions
    sensor_frame: SensorFrame = SensorFrame()

    kind = CASE_KIND

    @property
    def tree(self):
        from femcheck.robot.tree import RobotTree
        return RobotTree.from_case(self)


def _check_tree(ctx: Context, joints: tuple[TreeJoint, ...], markers, payload) -> tuple[TreeJoint, ...]:
    """Resolve default parents and branches; every reference names an earlier row (one line per problem)."""
    import dataclasses
    names: dict[str, int] = {}
    out = []
    for i, j in enumerate(joints):
        if j.name in names or j.name == "base":
            raise ctx.error(f"joints[{i}].name", f"{j.name!r} is used twice (or is the reserved 'base')")
        parent = j.parent or (out[-1].name if out else "base")
        if parent != "base" and parent not in names:
            raise ctx.error(f"joints[{i}].parent", f"{parent!r} is not an earlier row; expected 'base' or one of {list(names)}")
        branch = j.branch or (out[names[parent]].branch if parent != "base" else "main")
        if j.type == "prismatic" and j.stiffness_Nm_per_rad is not None:
            raise ctx.error(f"joints[{i}].stiffness_Nm_per_rad", "is a torsion spring; a prismatic row takes axial_stiffness_N_per_m")
        if j.type != "prismatic":
            for key in ("axial_stiffness_N_per_m", "guide_overlap_m", "guide_clearance_m"):
                if getattr(j, key) is not None:
                    raise ctx.error(f"joints[{i}].{key}", 'applies to prismatic rows only; expected type = "prismatic"')
        if j.coupling is not None:
            if not j.coupling:
                raise ctx.error(f"joints[{i}].coupling", "is empty; expected {row = c, ...}")
            for k, c in j.coupling.items():
                if k not in names:
                    raise ctx.error(f"joints[{i}].coupling.{k}", f"is not an earlier row; expected one of {list(names)}")
                if joints[names[k]].coupling is not None:
                    raise ctx.error(f"joints[{i}].coupling.{k}", "is itself coupled; couple to independent rows")
                if not math.isfinite(c):
                    raise ctx.error(f"joints[{i}].coupling.{k}", f"got {c}; expected a finite ratio")
        if j.coupling is not None and (j.backlash_rad is not None or j.backlash_torque_Nm is not None):
            raise ctx.error(f"joints[{i}].backlash_rad", "is set on a coupled row; backlash belongs to independent joints")
        names[j.name] = i
        out.append(dataclasses.replace(j, parent=parent, branch=branch))
    mnames = set()
    for i, m in enumerate(markers):
        if m.link not in names:
            raise ctx.error(f"markers[{i}].link", f"{m.link!r} is not a row; expected one of {list(names)}")
        if m.name in mnames:
            raise ctx.error(f"markers[{i}].name", f"{m.name!r} is used twice")
        mnames.add(m.name)
    if payload is not None and payload.link not in names:
        raise ctx.error("payload.link", f"{payload.link!r} is not a row; expected one of {list(names)}")
    if not any(j.mass_kg > 0 for j in out) and payload is None:
        raise ctx.error("joints", "no row has mass_kg > 0 and there is no [payload]: a self-weight model needs masses")
    return tuple(out)


def build(raw: dict, path) -> SerialTreeCase:
    """Validate a parsed TOML document into a :class:`SerialTreeCase` (errors name file and key)."""
    ctx = Context(path)
    parts = build_sections(ctx, raw, {"meta": Meta, "kinematics": TreeKinematics, "gravity": Gravity,
                                      "measurement": Measurement, "diagnosis": DiagnosisOptions,
                                      "sensor_frame": SensorFrame},
                           optional=("meta", "gravity", "measurement", "diagnosis", "sensor_frame"),
                           also_allowed=("joints", "markers", "payload"))
    for key in ("joints", "markers"):
        if not isinstance(raw.get(key), list) or not raw[key]:
            raise ctx.error(key, f"expected one or more [[{key}]] tables")
    joints = tuple(build_section(ctx, f"joints[{i}]", TreeJoint, t) for i, t in enumerate(raw["joints"]))
    markers = tuple(build_section(ctx, f"markers[{i}]", Marker, t) for i, t in enumerate(raw["markers"]))
    payload = build_section(ctx, "payload", Payload, raw["payload"]) if "payload" in raw else None
    joints = _check_tree(ctx, joints, markers, payload)
    if parts["measurement"].folds < 2:
        raise ctx.error("measurement.folds", f"got {parts['measurement'].folds}; expected >= 2")
    if parts["diagnosis"].fixed_point_passes < 1:
        raise ctx.error("diagnosis.fixed_point_passes", "expected >= 1")
    g = np.asarray(parts["gravity"].vector_m_per_s2)
    if not np.all(np.isfinite(g)) or np.linalg.norm(g) == 0:
        raise ctx.error("gravity.vector_m_per_s2", "expected a finite, non-zero vector")
    return SerialTreeCase(meta=parts["meta"], kinematics=parts["kinematics"], gravity=parts["gravity"], joints=joints,
                          markers=markers, payload=payload, measurement=parts["measurement"], diagnosis=parts["diagnosis"],
                          sensor_frame=parts["sensor_frame"])
