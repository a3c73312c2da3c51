"""A parallel device as arrays: every leg a serial chain of one-freedom joints (R or P screws) at the home pose.

A U joint is two R screws through its centre, an S joint three; a P joint is a translation along its link.
The model (:mod:`femcheck.parallel.chain_model`) and the beam FE (:mod:`femcheck.parallel.beam_fe`) read the
same :class:`ParallelDevice`; nothing in it changes after it is built (variants: :meth:`ParallelDevice.rotated`).

Conventions: base frame U, SI; the platform frame's pose is ``[x, y, z, rx, ry, rz]`` (m, rad, rotation
vector); twists ``[d; theta]`` and wrenches ``[F; M]`` at a stated point (``femcheck.kinematics.frames``).
"""
from __future__ import annotations

import dataclasses

import numpy as np

# laws called through their modules, so that the function a module holds is the one used (one implementation)
from femcheck.compliance import hertz_line_contact, hertz_point_contact, sections
from femcheck.compliance.sections import Section
from femcheck.errors import FemcheckError
from femcheck.kinematics.frames import rotvec_to_matrix, matrix_to_rotvec
from femcheck.kinematics.psu6 import POINT_LABELS  # noqa: F401  (the one definition of the labels)


class DeviceError(FemcheckError, ValueError):
    """A leg set that does not close or cannot reach a test point; ``key`` is the case key of the first such leg."""

    def __init__(self, key: str, message: str):
        self.key = key
        super().__init__(message)


@dataclasses.dataclass(frozen=True)
class LinkElement:
    """A link between centred joints ``start`` and ``end`` (indices into ``Leg.centres``): a cantilever clamped at
    the start and loaded at the end (``section`` None: rigid). ``x_axis`` (3,): section x at the home pose."""

    name: str
    start: int
    end: int
    section: Section | None
    E: float
    G: float
    x_axis: np.ndarray
    has_prismatic: bool
    #: the case's link description (section, material), for the solid links (:mod:`femcheck.parallel.solid_links`)
    spec: object = None


@dataclasses.dataclass(frozen=True)
class Leg:
    """One leg at the home pose (base frame, SI).

    centres (m, 3): centres of the R/U/S joints; dof_kind (nd,) 'R' | 'P'; dof_axis (nd, 3) unit;
    dof_point (nd, 3) a point of the axis (R; for P the link start); dof_joint (nd,) joint index;
    actuated_dof: index of the driven freedom; joint_centre (nj,) index into centres (-1 for P);
    links: the members; b_platform (3,): the last centre in the platform frame.
    limits: ((dof, low, high), ...) joint ranges; drive_compliance: m/N or rad/(N m); hertz_point: {joint: (E*, R*, F_min)}; hertz_line: {joint: (c_uc, c_ub, link)}.
    measured_law: {joint: (S (6, 6), centre, link)}: a contact-FE compliance (SI) at the joint centre ``centres[centre]``
    in the frame of link ``link`` (z along the link); measured_ladder: {joint: (loads_N (k,), approach_m (k,))} of
    the laws whose axial entry follows a force ladder (:func:`femcheck.parallel.chain_model.ladder_compliance`).
    """

    name: str
    case_index: int
    copy: int
    joint_types: tuple[str, ...]
    centres: np.ndarray
    dof_kind: tuple[str, ...]
    dof_axis: np.ndarray
    dof_point: np.ndarray
    dof_joint: np.ndarray
    actuated_dof: int
    joint_centre: np.ndarray
    links: tuple[LinkElement, ...]
    b_platform: np.ndarray
    drive_compliance: float
    hertz_point: dict
    hertz_line: dict
    limits: tuple = ()
    measured_law: dict = dataclasses.field(default_factory=dict)
    measured_ladder: dict = dataclasses.field(default_factory=dict)

    @property
    def n_dof(self) -> int:
        return len(self.dof_kind)

    @property
    def passive_dofs(self) -> np.ndarray:
        return np.array([k for k in range(self.n_dof) if k != self.actuated_dof], dtype=int)

    def dofs_before(self, joint: int) -> int:
        """Number of freedoms of the joints before ``joint`` (its centre moves with them only)."""
        return int(np.sum(self.dof_joint < joint))

    def dofs_through(self, joint: int) -> int:
        """Number of freedoms up to and including ``joint`` (the body after it moves with them)."""
        return int(np.sum(self.dof_joint <= joint))


@dataclasses.dataclass(frozen=True)
class ParallelDevice:
    """Legs, the platform's home pose and its TCP offset; ``beam_shear`` for the link cantilevers."""

    legs: tuple[Leg, ...]
    home_pose: np.ndarray
    tcp_offset: np.ndarray
    beam_shear: bool = False
    #: (L, E) factors on the compliance of element kind e in leg i that the case holds (``[model.element_scale]``);
    #: None = 1 everywhere. :func:`femcheck.parallel.chain_model.evaluate` multiplies any scale it is given by it
    element_scale: np.ndarray | None = None

    @property
    def n_legs(self) -> int:
        return len(self.legs)

    @property
    def element_names(self) -> tuple[str, ...]:
        """Names of the element kinds, in order of first appearance: link names, ``drive``, ``hertz_point``, ``hertz_line``,
        ``measured_law``."""
        names = []
        for leg in self.legs:
            for ln in leg.links:
                if ln.section is not None and ln.name not in names:
                    names.append(ln.name)
        names.append("drive")
        if any(leg.hertz_point for leg in self.legs):
            names.append("hertz_point")
        if any(leg.hertz_line for leg in self.legs):
            names.append("hertz_line")
        if any(leg.measured_law for leg in self.legs):
            names.append("measured_law")
        return tuple(names)

    def rotated(self, Q) -> "ParallelDevice":
        """The same device seen from a base frame rotated by ``Q`` (3, 3): every point, axis and the home pose turn."""
        Q = np.asarray(Q, dtype=float)
        R_home = rotvec_to_matrix(self.home_pose[3:])
        home = np.concatenate([Q @ self.home_pose[:3], matrix_to_rotvec(Q @ R_home @ Q.T)])
        legs = []
        for leg in self.legs:
            links = tuple(dataclasses.replace(ln, x_axis=Q @ ln.x_axis) for ln in leg.links)
            # the platform frame turns with the base (its orientation Q R Q^T), so b in the platform frame turns too
            legs.append(dataclasses.replace(leg, centres=leg.centres @ Q.T, dof_axis=leg.dof_axis @ Q.T,
                                            dof_point=leg.dof_point @ Q.T, links=links, b_platform=Q @ leg.b_platform))
        return dataclasses.replace(self, legs=tuple(legs), home_pose=home, tcp_offset=Q @ self.tcp_offset)


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def _normal_to(d):
    """A unit vector normal to ``d``, horizontal where possible: unit(z x d), else x."""
    a = np.cross([0.0, 0.0, 1.0], d)
    return _unit(a) if np.linalg.norm(a) > 1e-9 else np.array([1.0, 0.0, 0.0])


def _rz(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _resolve_leg(spec, i: int, copy: int, Q: np.ndarray, R_home, p_home, copies: int) -> Leg:
    who = f"leg {i} ({spec.name!r}{f', copy {copy + 1} of {copies}' if copies > 1 else ''})"
    centred = [k for k, j in enumerate(spec.joints) if j.type != "P"]
    centres = np.array([Q @ np.asarray(spec.joints[k].point_m, float) for k in centred])
    joint_centre = np.full(len(spec.joints), -1)
    joint_centre[centred] = np.arange(len(centred))
    link_dirs = np.array([_unit(centres[m + 1] - centres[m]) for m in range(len(centred) - 1)])

    def link_of(k):  # the link joint k sits in (P) or next to (the link before it; the first link for joint 0)
        if spec.joints[k].type == "P":
            return sum(1 for j in spec.joints[:k] if j.type != "P") - 1
        return max(int(joint_centre[k]) - 1, 0)

    kinds, axes, points, owner = [], [], [], []
    prismatic_links = set()
    for k, j in enumerate(spec.joints):
        given = None if j.axes is None else np.array([Q @ _unit(a) for a in j.axes])
        d = link_dirs[link_of(k)]
        if j.type == "P":
            m = link_of(k)
            prismatic_links.add(m)
            u = d if given is None else given[0]
            if abs(abs(u @ d) - 1.0) > 1e-9:
                raise DeviceError(f"legs[{i}].joints[{k}].axes", f"{who}: the P axis must lie along its link")
            kinds.append("P"), axes.append(u * np.sign(u @ d) if given is None else u), points.append(centres[m]), owner.append(k)
            continue
        c = centres[joint_centre[k]]
        if j.type == "R":
            ax = list(given)
        elif j.type == "U":
            a1 = given[0] if given is not None else _normal_to(d)
            if given is not None and len(given) == 2:
                ax = [a1, given[1]]
            else:
                a2 = np.cross(d, a1)
                if np.linalg.norm(a2) < 1e-9:
                    raise DeviceError(f"legs[{i}].joints[{k}].axes", f"{who}: the first U axis lies along the link")
                ax = [a1, _unit(a2)]
        elif j.type == "S":
            ax = list(given) if given is not None else list(np.eye(3))
        else:  # F: a clamp, no freedom
            ax = []
        for a in ax:
            kinds.append("R"), axes.append(a), points.append(c), owner.append(k)
    act_joint = next(k for k, j in enumerate(spec.joints) if j.actuated)
    actuated = owner.index(act_joint)

    links = []
    for m, ls in enumerate(spec.links):
        if ls.element == "rigid":
            section, E, G = None, 0.0, 0.0
        else:
            E, G = ls.material.E_Pa, ls.material.G_Pa
            section = (sections.tube_section(ls.outer_diameter_m, ls.inner_diameter_m) if ls.element == "tube"
                       else sections.rectangle_section(ls.width_m, ls.depth_m))
        d = link_dirs[m]
        x = _normal_to(d) if ls.x_axis is None else Q @ np.asarray(ls.x_axis, float)
        x = x - (x @ d) * d
        if np.linalg.norm(x) < 1e-9:
            raise DeviceError(f"legs[{i}].links[{m}].x_axis", f"{who}: the section x axis lies along the link")
        links.append(LinkElement(name=ls.name, start=m, end=m + 1, section=section, E=E, G=G, x_axis=_unit(x),
                                 has_prismatic=m in prismatic_links, spec=ls))

    hp, hl = {}, {}
    for k, j in enumerate(spec.joints):
        if j.hertz_point is not None:
            h = j.hertz_point
            E_star = hertz_point_contact.effective_modulus(h.ball_material.E_Pa, h.ball_material.nu,
                                                           h.seat_material.E_Pa, h.seat_material.nu)
            hp[k] = (float(E_star), float(hertz_point_contact.effective_radius(h.ball_radius_m, h.seat_curvature_1_per_m)),
                     h.min_contact_force_N)
        if j.hertz_line is not None:
            h = j.hertz_line
            E_star = hertz_point_contact.effective_modulus(h.pin_material.E_Pa, h.pin_material.nu,
                                                           h.bore_material.E_Pa, h.bore_material.nu)
            k_uc = hertz_line_contact.line_contact_stiffness(h.contact_length_m, E_star)
            k_ub = hertz_line_contact.pin_bending_stiffness(h.pin_material.E_Pa, h.pin_radius_m, h.pin_span_m)
            hl[k] = (float(1.0 / k_uc), float(1.0 / k_ub), link_of(k))
    ml, mlad = {}, {}
    for k, j in enumerate(spec.joints):
        if j.measured_law is not None:
            c = int(joint_centre[k])
            link = {"link_before": c - 1, "link_after": c, None: link_of(k)}[j.measured_law.frame]
            ml[k] = (np.array(j.measured_law.compliance, dtype=float), c, link)
            if j.measured_law.loads_N is not None:
                mlad[k] = (np.array(j.measured_law.loads_N, float), np.array(j.measured_law.approach_m, float))
    b = R_home.T @ (centres[-1] - p_home)
    name = spec.name if copies == 1 else f"{spec.name}{copy + 1}"
    return Leg(name=name, case_index=i, copy=copy, joint_types=tuple(j.type for j in spec.joints), centres=centres,
               dof_kind=tuple(kinds), dof_axis=np.array(axes), dof_point=np.array(points), dof_joint=np.array(owner),
               actuated_dof=actuated, joint_centre=joint_centre, links=tuple(links), b_platform=b,
               drive_compliance=spec.joints[act_joint].drive.compliance, hertz_point=hp, hertz_line=hl,
               limits=tuple((owner.index(k), *j.limits) for k, j in enumerate(spec.joints) if j.limits is not None),
               measured_law=ml, measured_ladder=mlad)


def device_from_case(case, check_points: bool = False) -> ParallelDevice:
    """Resolve the legs of a ``parallel_device`` case (symmetry copies included) into a :class:`ParallelDevice`.

    ``check_points``: also solve the inverse kinematics at the test points and check that the legs hold the
    platform (no free platform motion at the home pose); :class:`DeviceError` names the first failing leg.
    """
    home = np.asarray(case.platform.home_pose, dtype=float)
    R_home = rotvec_to_matrix(home[3:])
    copies = case.symmetry.copies
    if copies > 1 and (np.linalg.norm(home[:2]) > 1e-12 or np.linalg.norm(R_home[:2, 2]) > 1e-12):
        raise DeviceError("symmetry.copies", f"copies = {copies} needs the home pose on the base z axis, "
                                             "turned about z only (the copies turn about the base z axis)")
    legs = []
    for copy in range(copies):
        Q = _rz(2.0 * np.pi * copy / copies)
        for i, spec in enumerate(case.legs):
            legs.append(_resolve_leg(spec, i, copy, Q, R_home, home[:3], copies))
    dev = ParallelDevice(legs=tuple(legs), home_pose=home, tcp_offset=np.asarray(case.platform.tcp_offset_m, float),
                         beam_shear=case.model.beam_shear)
    given = getattr(case.model, "element_scale", None)
    if given:
        names = dev.element_names
        f = np.ones((dev.n_legs, len(names)))
        for kind, values in dict(given).items():
            if kind not in names:
                raise DeviceError(f"model.element_scale.{kind}", f"{kind!r} is not an element kind of this device; "
                                                                  f"expected one of {list(names)}")
            if len(values) != dev.n_legs:
                raise DeviceError(f"model.element_scale.{kind}", f"has {len(values)} factors; expected one per leg "
                                                                  f"({dev.n_legs}, symmetry copies included)")
            f[:, names.index(kind)] = values
        dev = dataclasses.replace(dev, element_scale=f)
    if check_points:
        _check_device(case, dev)
    return dev


def test_points(case) -> np.ndarray:
    """(9, 6) platform poses of the test cube: P0 = nominal TCP, P1..P8 = P0 + edge/2 * corner_signs (TCP positions)."""
    w = case.workspace
    centre = np.asarray(w.nominal_tcp_m, dtype=float)
    pos = np.vstack([centre, centre + 0.5 * w.cube_edge_m * np.asarray(w.corner_signs, dtype=float)])
    return np.hstack([pos, np.tile(np.asarray(w.rotation, float), (9, 1))])


def _check_device(case, dev: ParallelDevice) -> None:
    from femcheck.parallel.leg_kinematics import TOL, constraint_rank, solve_legs
    home = dev.home_pose.copy()
    home[:3] += rotvec_to_matrix(home[3:]) @ dev.tcp_offset  # the TCP at the home pose
    rank, free = constraint_rank(dev, home[None])
    free = np.where(np.abs(free) < 1e-9, 0.0, free)
    if rank < 6:
        raise DeviceError("legs", f"with released joints the legs leave the platform free to move at the home pose "
                                  f"along the twist {np.array2string(free, precision=3, suppress_small=True)} (TCP, [d; theta]); "
                                  "check the joint axes")
    poses = test_points(case)
    state = solve_legs(dev, poses)
    for li, leg in enumerate(dev.legs):
        bad = np.flatnonzero(~state.legs[li].ok)
        if bad.size:
            k = int(bad[0])
            s = state.legs[li]
            why = (f"inverse kinematics residual {s.residual[k]:.3g}" if s.residual[k] >= TOL else
                   "joint " + ", ".join(f"{s.q[k, d]:.4g} outside [{lo}, {hi}]" for d, lo, hi in leg.limits
                                        if not lo <= s.q[k, d] <= hi))
            raise DeviceError(f"legs[{leg.case_index}]",
                              f"leg {li} ({leg.name!r}) cannot reach test point {POINT_LABELS[k]} "
                              f"{np.array2string(poses[k, :3] * 1e3, precision=1)} mm ({why}); "
                              "move the test cube or change this leg")
