"""The 6-PSU layout of a parallel device: the paper's tables (seed 000 §3-4, docs/conventions.md §2) read from
a ``parallel_device`` case whose legs are the 6-PSU's, and the legs written from those tables.

A leg of the layout is ``F-P*-S-U``: the guideway bar clamped at A_i (F), the slider driven along the rail
(P*, an ``axial`` drive: cable and motor shaft), the ball of the spherical joint at B_i (S, ``hertz_point``) and
the cross of the universal joint at C_i (U, ``hertz_line``); links: the guideway bar A_i -> B_i (a ``bar``, its
length the slider position s_i) and the proximal tube B_i -> C_i. Six such legs in the paper's pairs
(``theta_b,i = 120 k + s_i alpha_b``, ``theta_p,i = 120 k + s_i (60 - alpha_p)``, pair k = i // 2, s_i = -1 for
even i) with one set of parts make the layout.

:func:`psu_layout` reads the tables from the legs once per case (None for any other device); the case offers
them as ``case.geometry``, ``case.guideway``, ... (:class:`~femcheck.case.parallel_device.ParallelDeviceCase`),
so the 6-PSU's chain model, device FE, diagnosis and reports read the numbers of the legs. :func:`layout_legs`
writes the legs of a layout (a case variant that changes a table: :func:`femcheck.case.registry.with_params`).
"""
from __future__ import annotations

import copy
import dataclasses
import functools
from dataclasses import dataclass

import numpy as np

from femcheck.case.device_options import ActuationFE
from femcheck.case.joint_contact_tables import HertzLine
from femcheck.case.schema import Material, option, quantity

#: the tables of the layout: ``case.<table>`` and the dotted keys ``<table>.<field>`` of a case variant
TABLES = ("geometry", "guideway", "proximal_link", "spherical_joint", "universal_joint", "actuation")
#: the layout's agreement between legs and with the paper's pattern: relative to the base radius (rounding only)
_TOL = 1e-9


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


#: the universal joint's table: cross pins in yoke bores at C_i (Hertz line contact + simply supported pin
#: bending), every leg's ``hertz_line`` at its U joint
UniversalJoint = HertzLine


@dataclass(frozen=True)
class Actuation:
    """DC motor -> capstan -> cable -> slider (every leg's ``drive``), and how the device FE models it."""
    cable_diameter_m: float = quantity("m")
    cable_modulus_Pa: float = quantity("Pa")
    cable_length_m: float = quantity("m")
    shaft_diameter_m: float = quantity("m")
    shaft_length_m: float = quantity("m")
    shaft_G_Pa: float = quantity("Pa")
    capstan_radius_m: float = quantity("m")
    fe: ActuationFE = ActuationFE()


_DRIVE_KEYS = ("cable_diameter_m", "cable_modulus_Pa", "cable_length_m", "shaft_diameter_m", "shaft_length_m",
               "shaft_G_Pa", "capstan_radius_m")


@dataclass(frozen=True)
class PSULayout:
    """The paper's tables of a 6-PSU device and its joint points at the home pose (SI).

    base_points (6, 3): clamp points A_i in the base frame; platform_points (6, 3): U-joint centres C_i in the
    platform frame; base_angles_rad, platform_angles_rad (6,): their polar angles.
    """
    geometry: Geometry
    guideway: Guideway
    proximal_link: ProximalLink
    spherical_joint: SphericalJoint
    universal_joint: UniversalJoint
    actuation: Actuation
    base_points: np.ndarray = dataclasses.field(repr=False, compare=False)
    platform_points: np.ndarray = dataclasses.field(repr=False, compare=False)

    @property
    def base_angles_rad(self) -> np.ndarray:
        return np.arctan2(self.base_points[:, 1], self.base_points[:, 0])

    @property
    def platform_angles_rad(self) -> np.ndarray:
        return np.arctan2(self.platform_points[:, 1], self.platform_points[:, 0])


def _pattern(half_angle_deg: float, platform: bool) -> np.ndarray:
    """(6,) the paper's polar angles (rad) of the base clamps or the platform joints (docs/conventions.md §2)."""
    i = np.arange(6)
    s = np.where(i % 2 == 0, -1.0, 1.0)
    return np.deg2rad(120.0 * (i // 2) + s * ((60.0 - half_angle_deg) if platform else half_angle_deg))


def psu_layout(case) -> PSULayout | None:
    """The 6-PSU tables of ``case`` (a parallel_device case), or None where its legs are not the 6-PSU's (pattern,
    parts alike in every leg, one rail length). Read once per case (cases are immutable)."""
    return _layout(case)


def _parts(leg) -> tuple:
    """What must be alike in every leg of the layout: the link sections, the joint laws, the drive."""
    gw, tube = leg.links
    j = leg.joints
    return ((gw.material, gw.width_m, gw.depth_m), (tube.material, tube.outer_diameter_m, tube.inner_diameter_m),
            j[1].drive, j[2].hertz_point, j[3].hertz_line, j[2].measured_law, j[3].measured_law)


def _round(x) -> float:
    return float(f"{float(x):.12g}") + 0.0     # + 0.0: no negative zero


def _rpy_deg(R: np.ndarray) -> tuple[float, float, float]:
    """Roll-pitch-yaw (deg) of R = Rz Ry Rx (the inverse of :func:`femcheck.kinematics.frames.rpy_deg_to_matrix`)."""
    return tuple(float(v) for v in np.rad2deg([np.arctan2(R[2, 1], R[2, 2]), np.arcsin(-np.clip(R[2, 0], -1, 1)),
                                               np.arctan2(R[1, 0], R[0, 0])]))


@functools.lru_cache(maxsize=64)
def _layout(case) -> PSULayout | None:
    from femcheck.kinematics.frames import rotvec_to_matrix
    legs = case.legs
    if case.symmetry.copies != 1 or len(legs) != 6:
        return None
    if any(tuple(j.type for j in leg.joints) != ("F", "P", "S", "U") or len(leg.links) != 2
           or (leg.links[0].element, leg.links[1].element) != ("bar", "tube") or leg.joints[1].axes is None
           or leg.joints[1].limits is None or leg.joints[2].hertz_point is None or leg.joints[3].hertz_line is None
           or leg.joints[2].measured_law is not None or leg.joints[3].measured_law is not None for leg in legs):
        return None
    parts = [_parts(leg) for leg in legs]
    drive = legs[0].joints[1].drive
    if any(p != parts[0] for p in parts[1:]) or drive.law != "axial" or drive.stiffness is not None \
            or drive.gear_ratio != 1.0:
        return None
    A = np.array([leg.joints[0].point_m for leg in legs], float)
    B = np.array([leg.joints[2].point_m for leg in legs], float)
    C = np.array([leg.joints[3].point_m for leg in legs], float)
    E = np.array([leg.joints[1].axes[0] for leg in legs], float)
    E /= np.linalg.norm(E, axis=1, keepdims=True)
    e = E[0]
    home = np.asarray(case.platform.home_pose, float)
    c = (C - home[:3]) @ rotvec_to_matrix(home[3:])         # C_i in the platform frame
    R_b, R_p = float(np.hypot(*A[0, :2])), float(np.hypot(*c[0, :2]))
    alpha_b = -float(np.rad2deg(np.arctan2(A[0, 1], A[0, 0])))
    alpha_p = 60.0 + float(np.rad2deg(np.arctan2(c[0, 1], c[0, 0])))
    s_home = (B - A) @ e
    L2 = np.linalg.norm(C - B, axis=1)
    limits = np.array([leg.joints[1].limits for leg in legs], float)
    lo, hi = s_home + limits[:, 0], s_home + limits[:, 1]
    tol = _TOL * max(R_b, 1e-3)

    def on_circle(P, R, th):
        return np.abs(P[:, :2] - R * np.stack([np.cos(th), np.sin(th)], 1)).max() < tol

    if not (R_b > 0 and R_p > 0 and np.abs(E - e).max() < _TOL and on_circle(A, R_b, _pattern(alpha_b, False))
            and on_circle(c, R_p, _pattern(alpha_p, True)) and np.ptp(A[:, 2]) < tol and np.abs(c[:, 2]).max() < tol
            and np.abs(B - A - s_home[:, None] * e).max() < tol and np.ptp(L2) < tol
            and np.ptp(lo) < tol and np.ptp(hi) < tol):
        return None
    gw, tube = legs[0].links
    hp, hl = legs[0].joints[2].hertz_point, legs[0].joints[3].hertz_line
    # the tables' numbers to 12 significant digits: the file's points carry the layout to rounding (1e-16), and the
    # tables read as written (0.18, not 0.17999999999999997); the points themselves are used as given
    R_b, R_p, alpha_b, alpha_p = (_round(v) for v in (R_b, R_p, alpha_b, alpha_p))
    geometry = Geometry(
        base_radius_m=R_b, base_pair_half_angle_deg=alpha_b, platform_radius_m=R_p,
        platform_pair_half_angle_deg=alpha_p, platform_pair_rotation_deg=-60.0, base_height_m=float(A[0, 2]),
        guideway_direction=tuple(float(v) for v in e), proximal_link_length_m=_round(L2[0]),
        tcp_offset_m=tuple(float(v) for v in case.platform.tcp_offset_m),
        platform_rpy_deg=tuple(_round(v) for v in _rpy_deg(rotvec_to_matrix(np.asarray(case.workspace.rotation, float)))),
        rail_length_m=_round(hi[0]), min_slider_position_m=_round(lo[0]))
    return PSULayout(
        geometry=geometry,
        guideway=Guideway(material=gw.material, width_radial_m=gw.width_m, depth_tangential_m=gw.depth_m),
        proximal_link=ProximalLink(material=tube.material, outer_diameter_m=tube.outer_diameter_m,
                                   inner_diameter_m=tube.inner_diameter_m),
        spherical_joint=SphericalJoint(**{f.name: getattr(hp, f.name) for f in dataclasses.fields(SphericalJoint)}),
        universal_joint=UniversalJoint(**{f.name: getattr(hl, f.name) for f in dataclasses.fields(UniversalJoint)}),
        actuation=Actuation(**{k: getattr(drive, k) for k in _DRIVE_KEYS}, fe=case.actuation_options.fe),
        base_points=A, platform_points=c)


def _table(obj) -> dict:
    """A layout table as its TOML table (materials by name)."""
    return {f.name: (getattr(obj, f.name).name if isinstance(getattr(obj, f.name), Material) else getattr(obj, f.name))
            for f in dataclasses.fields(obj) if f.name != "fe"}


def layout_legs(tables: dict[str, dict], home_tcp, rotation) -> tuple[list[dict], list[float]]:
    """The six ``[[legs]]`` tables (TOML) of the layout ``tables`` ({table: {field: value}}, materials by name)
    and the platform home pose (m, rad): the platform at the TCP ``home_tcp`` (m) with the rotation vector
    ``rotation`` (rad); each slider where its leg closes there (docs/conventions.md §2)."""
    from femcheck.kinematics.frames import rotvec_to_matrix
    g, gw, pl, sj, uj, act = (tables[t] for t in TABLES)
    th_b, th_p = _pattern(g["base_pair_half_angle_deg"], False), _pattern(g["platform_pair_half_angle_deg"], True)
    e = np.asarray(g["guideway_direction"], float)
    A = np.stack([g["base_radius_m"] * np.cos(th_b), g["base_radius_m"] * np.sin(th_b), np.full(6, g["base_height_m"])], 1)
    c = np.stack([g["platform_radius_m"] * np.cos(th_p), g["platform_radius_m"] * np.sin(th_p), np.zeros(6)], 1)
    R = rotvec_to_matrix(np.asarray(rotation, float))
    origin = np.asarray(home_tcp, float) - R @ np.asarray(g["tcp_offset_m"], float)
    C = origin + c @ R.T
    d = C - A
    de = d @ e
    s = de - np.sqrt(g["proximal_link_length_m"] ** 2 - np.sum((d - de[:, None] * e) ** 2, axis=1))
    B = A + s[:, None] * e
    radial = np.stack([np.cos(th_b), np.sin(th_b), np.zeros(6)], 1)
    x = radial - (radial @ e)[:, None] * e
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    vec = lambda v: [float(t) for t in v]
    legs = [{
        "name": f"chain{i}",
        "links": [{"name": "guideway", "element": "bar", "material": gw["material"], "width_m": gw["width_radial_m"],
                   "depth_m": gw["depth_tangential_m"], "x_axis": vec(x[i])},
                  {"name": "proximal_link", "element": "tube", "material": pl["material"],
                   "outer_diameter_m": pl["outer_diameter_m"], "inner_diameter_m": pl["inner_diameter_m"]}],
        "joints": [{"type": "F", "point_m": vec(A[i])},
                   {"type": "P", "actuated": True, "axes": [vec(e)],
                    "limits": [float(g["min_slider_position_m"] - s[i]), float(g["rail_length_m"] - s[i])],
                    "drive": {"law": "axial", **{k: act[k] for k in _DRIVE_KEYS}}},
                   {"type": "S", "point_m": vec(B[i]), "hertz_point": dict(sj)},
                   {"type": "U", "point_m": vec(C[i]), "hertz_line": dict(uj)}],
    } for i in range(6)]
    return legs, vec(origin) + vec(rotation)


def with_layout_params(case, raw: dict, dotted: dict) -> dict:
    """Apply the dotted keys of ``dotted`` that name a layout table (``guideway.width_radial_m``,
    ``geometry.base_radius_m``, ...; not ``actuation.fe.*``, a section of the case) to the document ``raw`` of
    ``case``: the legs and the platform home pose are written again from the changed tables. Returns the other
    keys. A case that is not a 6-PSU layout returns ``dotted`` unchanged (its keys are then unknown)."""
    mine = {k: v for k, v in dotted.items() if k.split(".")[0] in TABLES and not k.startswith("actuation.fe.")}
    layout = psu_layout(case) if mine else None
    if layout is None:
        return dotted
    from femcheck.case.schema import Context, build_materials, build_section
    from femcheck.errors import CaseError
    tables = {t: _table(getattr(layout, t)) for t in TABLES}
    for key, value in mine.items():
        t, _, name = key.partition(".")
        if name not in tables[t]:
            raise CaseError(case.source, key, f"unknown key; expected one of {sorted(tables[t])}")
        tables[t][name] = value
    # materials written in the same call (a tube alloy of its own) are known to the tables that name them
    materials = copy.deepcopy(raw.get("materials", {}))
    for key, value in dotted.items():
        parts = key.split(".")
        if len(parts) == 3 and parts[0] == "materials":
            materials.setdefault(parts[1], {})[parts[2]] = value
    ctx = Context(case.source, build_materials(Context(case.source), materials))
    for t, cls in zip(TABLES, (Geometry, Guideway, ProximalLink, SphericalJoint, UniversalJoint, Actuation)):
        build_section(ctx, t, cls, tables[t])              # validate the changed tables (errors name the key)
    from femcheck.kinematics.frames import matrix_to_rotvec, rpy_deg_to_matrix
    w = raw.setdefault("workspace", {})
    # the platform orientation of the tables is the test cube's (the paper's platform_rpy_deg)
    w["rotation"] = [float(v) for v in matrix_to_rotvec(rpy_deg_to_matrix(tables["geometry"]["platform_rpy_deg"]))]
    legs, home = layout_legs(tables, w.get("nominal_tcp_m"), w["rotation"])
    raw["legs"] = legs
    raw.setdefault("platform", {})["home_pose"] = home
    raw["platform"]["tcp_offset_m"] = list(tables["geometry"]["tcp_offset_m"])
    return {k: v for k, v in dotted.items() if k not in mine}
