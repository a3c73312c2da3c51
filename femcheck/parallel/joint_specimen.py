"""The passive joints of a parallel device measured by their own contact FE (ball in seat, cross pins in yokes).

The analytical chain takes a ball in its seat (``hertz_point``) as a Hertz point contact and a U joint's pins in
their bores (``hertz_line``) as Hertz line contact plus pin bending. The device FE
(:mod:`femcheck.parallel.beam_fe`) takes them from the contact FE of the joint instead
(:mod:`femcheck.fe_device.joint_fe`: meshed ball and seat, or cross and yokes, P2, penalty contact), built from
the joint's own dimensions and materials in the case. Each distinct joint is measured once over a **force
ladder** (:class:`femcheck.fe_device.joint_laws.MeasuredJointLaw`) and cached on disk keyed by its inputs
(geometry, materials, mesh level, ladder, joint-FE code).

A joint's specimen (:class:`JointSpecimen`) carries what the joint FE reads: the joint's ``hertz_point`` or
``hertz_line`` table (radius, lengths, materials) and the solid details a case of this kind does not describe
(seat disc, yoke walls, pin clearance 10 um, friction, mesh sizes), at the defaults of
:class:`femcheck.case.haptic_6psu_solid.SolidModel`; the yoke wall and the rigid hub are narrowed where the
defaults do not fit between the pins' span and contact length.

The ladder spans the joint forces of the device at its nine test points under the test force in every
direction: the force resultant is the same in every joint of a leg (no load along the leg), and with released
joints the leg forces follow from statics alone for these devices (one constraint per leg), so the ladder does
not depend on any compliance law. An R joint's pin in its bores (``hertz_line`` on an R joint) is the cross's
mesh with its hub held (``hub_held``): the link yoke's pin bears in its two bores and bends to the held hub, as a
clevis pin in the other body's eye.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.case.haptic_6psu_solid import SolidModel

#: the ladder reaches this factor above the largest joint force at the test points
LADDER_MARGIN = 1.25
LADDER_LEVELS = 7
#: universal joint: the ladder's first force, as a fraction of its last (the pins carry no preload floor)
UNIVERSAL_FLOOR = 1.0 / 32.0


@dataclasses.dataclass(frozen=True)
class JointSpecimen:
    """What the joint contact FE reads of one joint (module doc): the ball (``spherical_joint``: a
    ``hertz_point`` table) or the pins (``universal_joint``: a ``hertz_line`` table), the other None."""

    spherical_joint: object = None
    universal_joint: object = None
    solid: SolidModel = SolidModel()
    #: a revolute's pin in its bores: the cross's hub held, so only the link yoke's pin and bores carry the load
    hub_held: bool = False


@dataclasses.dataclass(frozen=True)
class DeviceJoint:
    """A passive joint of the case with a contact-FE geometry: ``leg`` (index of ``[[legs]]``), ``joint`` (index
    in its ``joints``), ``kind`` 'spherical' | 'universal' | 'revolute', its ``specimen``."""

    leg: int
    joint: int
    kind: str
    specimen: JointSpecimen

    @property
    def fe_joint(self) -> str:
        """The joint contact FE that measures it (:mod:`femcheck.fe_device.joint_fe`: a revolute is the cross
        with its hub held)."""
        return "universal" if self.kind == "revolute" else self.kind


#: share of the room between a pin's bore and the next arm (the cross's other pin) the yoke wall may take, and of
#: the pin length inside the span the rigid hub may tie
YOKE_ROOM_SHARE = 0.9
HUB_ROOM_SHARE = 0.8


def _cross_fitted(pins) -> SolidModel:
    """The default solid details with the yoke wall and the hub fitted into the pins' span where the defaults
    do not fit (the arms of the two pins must not meet: span - contact length > 2 (r + clearance + wall))."""
    base = SolidModel()
    uj = base.universal_joint
    rb = float(pins.pin_radius_m) + uj.pin_clearance_m
    room = 0.5 * (float(pins.pin_span_m) - float(pins.contact_length_m))
    wall = min(uj.yoke_wall_m, YOKE_ROOM_SHARE * (room - rb))
    hub = min(uj.hub_half_length_m, HUB_ROOM_SHARE * room)
    if wall <= 0:
        from femcheck.errors import FemcheckError
        raise FemcheckError(f"hertz_line: pin_span_m - contact_length_m = {2 * room:.4g} m leaves no room for the "
                            f"yoke arms around pins of radius {pins.pin_radius_m} m (the joint's contact FE)")
    return dataclasses.replace(base, universal_joint=dataclasses.replace(uj, yoke_wall_m=wall, hub_half_length_m=hub))


def device_joints(case) -> tuple[DeviceJoint, ...]:
    """The case's joints that have a contact FE: S joints with ``hertz_point``, U and R joints with ``hertz_line``
    (an R joint: the cross's mesh with its hub held, so the link yoke's pin in its two bores is the revolute)."""
    out = []
    for i, leg in enumerate(case.legs):
        for k, j in enumerate(leg.joints):
            if j.type == "S" and j.hertz_point is not None:
                out.append(DeviceJoint(i, k, "spherical", JointSpecimen(spherical_joint=j.hertz_point)))
            elif j.type in ("U", "R") and j.hertz_line is not None:
                out.append(DeviceJoint(i, k, "universal" if j.type == "U" else "revolute", JointSpecimen(universal_joint=j.hertz_line,
                                                                        solid=_cross_fitted(j.hertz_line),
                                                                        hub_held=j.type == "R")))
    return tuple(out)


def leg_forces(case) -> np.ndarray:
    """(9, n_directions, L) N: the force resultant each leg carries at the test points under the test force
    (released-joint statics, :func:`femcheck.parallel.chain_model.evaluate` at the simplified level)."""
    from femcheck.kinematics.directions import direction_unit
    from femcheck.parallel.chain_model import evaluate
    from femcheck.parallel.device import test_points
    from femcheck.parallel.leg_kinematics import solve_legs

    P = test_points(case)
    state = solve_legs(case.device, P)
    out = []
    for d in case.loads.directions:
        W = np.concatenate([case.loads.test_N * direction_unit(d), np.zeros(3)])
        r = evaluate(case.device, P, W, model="simplified", joints="released", state=state)
        out.append(np.linalg.norm(r.leg_wrench[..., :3], axis=-1))
    return np.stack(out, axis=1)


def force_ladder(case, joint: DeviceJoint, forces: np.ndarray | None = None) -> np.ndarray:
    """(LADDER_LEVELS,) N: geometric ladder over the forces of the joint's leg (every copy) at the test points,
    from the ball's ``min_contact_force_N`` (pins: the top over 32) to 1.25 x the largest."""
    forces = leg_forces(case) if forces is None else forces
    legs = [li for li, lg in enumerate(case.device.legs) if lg.case_index == joint.leg]
    f_max = float(forces[..., legs].max())
    if joint.kind == "spherical":
        f_lo = float(joint.specimen.spherical_joint.min_contact_force_N)
    else:
        f_lo = LADDER_MARGIN * f_max * UNIVERSAL_FLOOR
    f_hi = max(LADDER_MARGIN * f_max, 4.0 * f_lo)
    return np.geomspace(f_lo, f_hi, LADDER_LEVELS)


@dataclasses.dataclass(frozen=True)
class DeviceJointLaws:
    """The contact-FE laws of a device's joints: ``laws`` {(leg, joint): (kind, MeasuredJointLaw)} (kind as
    :class:`DeviceJoint`), keys as
    :class:`DeviceJoint` (``[[legs]]`` index, joint index)."""

    laws: dict

    def sources(self) -> dict:
        """{"<leg name>.joints[k]": "contact_fe"} for the report."""
        return {f"legs[{i}].joints[{k}]": "contact_fe" for (i, k) in self.laws}

    def details(self) -> dict:
        return {f"legs[{i}].joints[{k}]": {"kind": kind, **law.summary()} for (i, k), (kind, law) in self.laws.items()}


def measure_device_joint_laws(case, mesh: str = "coarse", use_cache: bool = True, progress=None) -> DeviceJointLaws:
    """Every contact-FE joint of ``case`` measured (or read from the cache) over its ladder; identical joints
    (same specimen and ladder, e.g. symmetric legs) are measured once."""
    from femcheck.fe_device.joint_laws import measure_joint_law

    forces = leg_forces(case)
    done, out = {}, {}
    for j in device_joints(case):
        ladder = force_ladder(case, j, forces)
        key = (j.kind, j.specimen, tuple(np.round(ladder, 12)))
        if key not in done:
            done[key] = measure_joint_law(j.specimen, j.fe_joint, mesh, ladder, use_cache)
            if progress:
                progress(f"{j.kind} joint of legs[{j.leg}]")
        out[(j.leg, j.joint)] = (j.kind, done[key])
    return DeviceJointLaws(out)


def cached(case, mesh: str = "coarse") -> dict:
    """{(leg, joint): whether its law is in the cache}."""
    from femcheck.fe_device.joint_laws import _cache_key, _cache_path

    forces = leg_forces(case)
    return {(j.leg, j.joint): _cache_path(_cache_key(j.specimen, j.fe_joint, mesh, force_ladder(case, j, forces))).is_file()
            for j in device_joints(case)}
