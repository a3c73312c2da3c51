"""The device FE model at test points: super-elements of every leg, then all load cases.

Work split (what runs where): the link super-element is the same for every leg and point (the link
length L2 is fixed; only its orientation changes), so it is built once per mesh level; each leg needs
its own guideway super-element (cantilever length s_i differs per leg and point) — these FE solves
are independent tasks (:func:`guideway_task`) that the verification runs in parallel processes. The
rest (joints, leg condensation, rigid platform, load protocol) is small dense algebra.
"""
from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np

from femcheck.fe_device.joints import FE_JOINTS, LEVELS
from femcheck.fe_device.loads import LoadCaseResult, load_case
from femcheck.fe_device.parts import SuperElement, guideway_element, link_element
from femcheck.fe_device.substructure import platform_matrices

log = logging.getLogger(__name__)


def guideway_task(case, length_m: float, kind: str, size_m: float) -> SuperElement:
    """One guideway FE solve (picklable entry point for worker processes)."""
    return guideway_element(case, float(length_m), kind, size_m)


def build_link(case, kind: str, size_m: float) -> SuperElement:
    """The link super-element (once per mesh level)."""
    return link_element(case, kind, size_m)


@dataclasses.dataclass(frozen=True)
class PointModel:
    """Everything the FE model of one test point needs (SI, frame U): ``point`` label, ``A`` (6, 3),
    ``B``, ``C`` (6, 3), ``u`` (6, 3), ``tcp`` (3,), part frames ``R_A``, ``R_B`` (6, 3, 3), ``G`` (6, 6, 6)
    platform matrices, super-elements ``guideways`` (6) and ``link``."""

    point: str
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    u: np.ndarray
    tcp: np.ndarray
    R_A: np.ndarray
    R_B: np.ndarray
    G: np.ndarray
    guideways: tuple
    link: SuperElement

    @property
    def K_lg(self) -> np.ndarray:
        return np.stack([g.K for g in self.guideways])


def point_geometry(case, points):
    """Leg geometry of ``points`` (labels) -> LegGeometry and the sliders (n, 6) m."""
    from femcheck.kinematics.points import point_set
    return point_set(case, points).legs


def point_model(case, legs, k: int, point: str, guideways, link: SuperElement) -> PointModel:
    from femcheck.kinematics.frames import guideway_frames, link_frames
    u = legs.u[k]
    return PointModel(point=point, A=legs.A, B=legs.B[k], C=legs.C[k], u=u, tcp=legs.tcp[k],
                      R_A=guideway_frames(case), R_B=link_frames(u), G=platform_matrices(legs.C[k], legs.tcp[k]),
                      guideways=tuple(guideways), link=link)


def actuation_springs_at(case, model: PointModel):
    """(6,) N/m actuation springs of the point's legs from the actuation FE (``[actuation.fe] model =
    "elements"``, :mod:`femcheck.fe_device.actuation_fe`), or None: eq. 44 from the FE's own springs
    (:func:`femcheck.fe_device.contact_scales.device_springs`)."""
    return actuation_at(case, model)[0]


def actuation_at(case, model: PointModel):
    """(k_act (6,) N/m or None, K_lg (6, 6, 6)) for the device FE of one point.

    With ``[actuation.fe] model = "elements"``: the axial springs of the condensed actuation FE, and the guideway
    tip stiffnesses (frame A, local z = rail) plus the cable pretension's transverse geometric stiffness
    τ (1/l1 + 1/l2a) on the two translations across the rail (the strands run from pulleys on the base to the
    slider). Otherwise (None, ``model.K_lg``): eq. 44 from the FE's own springs, no cable across the rail.
    """
    if case.actuation.fe.model != "elements":
        return None, model.K_lg
    from femcheck.fe_device.actuation_fe import actuation_legs
    e = _rail(case)
    k_act, k_t = actuation_legs(case, (model.B - model.A) @ e, e)
    K_lg = model.K_lg.copy()
    K_lg[:, 0, 0] += k_t
    K_lg[:, 1, 1] += k_t
    return k_act, K_lg


def _rail(case) -> np.ndarray:
    e = np.asarray(case.geometry.guideway_direction, float)
    return e / np.linalg.norm(e)


def min_strand_tension(case, model: PointModel, cases: dict, k_act) -> float:
    """Lowest cable-strand tension (N) over the detailed load states of ``cases`` (linear actuation FE: the
    pretension plus each strand's share of the leg's actuation force k_act r_act); <= 0 means a strand went
    slack and the linear (both strands taut) model does not hold there."""
    from femcheck.fe_device.actuation_fe import leg_actuation
    e = _rail(case)
    legs = [leg_actuation(case, s, e) for s in (model.B - model.A) @ e]
    t_min = np.inf
    for (lvl, _, _), res in cases.items():
        if lvl != "detailed":
            continue
        for st in res.states:
            r_act = st.legs.interior(st.u_C)["q"][:, st.legs.blocks["act"]].reshape(6, -1)[:, 0]
            for leg, F in zip(legs, np.asarray(k_act) * r_act):
                t_min = min(t_min, float(leg.strand_tensions(F).min()))
    return t_min


@dataclasses.dataclass(frozen=True)
class PointResult:
    """All load cases of one point: ``cases`` {(level, joints, direction): LoadCaseResult}; ``seconds``;
    ``min_strand_tension_N``: lowest cable tension of the actuation FE over the detailed states (None when
    the actuation is eq. 44's spring)."""

    point: str
    cases: dict
    seconds: float
    min_strand_tension_N: float | None = None


def solve_point(case, model: PointModel, levels=LEVELS, joints=FE_JOINTS, directions=None,
                friction=None, joint_laws=None, springs=None) -> PointResult:
    """Every (level, joints, direction) load case of one point (:func:`femcheck.fe_device.loads.load_case`).

    ``contact`` joints exist at the detailed level only; ``friction`` (:class:`.joint_friction.JointFriction`)
    defaults to the case's, with the theoretical tilt slip ratio 1; ``joint_laws``
    (:class:`.joint_laws.JointLaws`): the contact-FE-measured joint laws (None: the closed forms); ``springs``: the
    FE's closed-form springs (default :func:`.contact_scales.device_springs` of the case).
    """
    from femcheck.fe_device.contact_scales import device_springs
    from femcheck.fe_device.joint_friction import joint_friction
    t0 = time.perf_counter()
    params = springs or device_springs(case)   # the FE's own springs, never the analytical model's parameters
    friction = friction or joint_friction(case, springs=params)
    directions = tuple(directions or case.loads.directions)
    k_act, K_lg = actuation_at(case, model)
    out: dict[tuple, LoadCaseResult] = {}
    for lvl in levels:
        for j in joints:
            if j == "contact" and lvl != "detailed":
                continue
            for d in directions:
                # the simplified level has no actuation element (docs/conventions.md §5), so no cable across the rail
                K_guide = K_lg if lvl == "detailed" else model.K_lg
                out[(lvl, j, d)] = load_case(case, K_guide, model.link.K, model.R_A, model.R_B, model.G,
                                             lvl, j, d, params, friction, k_act, joint_laws)
    t_min = None
    if k_act is not None:
        t_min = min_strand_tension(case, model, out, k_act)
        if t_min <= 0:
            log.warning("%s: a cable strand goes slack (tension %.1f N < 0): raise [actuation.fe] "
                        "cable_pretension_N; the linear actuation FE assumes taut strands", model.point, t_min)
    return PointResult(model.point, out, time.perf_counter() - t0, t_min)
