"""The model a diagnosis checks: predicts every dial reading of a :class:`~femcheck.measured.Readings`.

A reading model maps (pose, applied TCP force, element compliance scales, joint-rotation compliance) to
the TCP translation (m). Effects (``femcheck.diagnose.effects``) act on a :class:`WorkingState` before and
after that call: they change the effective force (friction), the compliance of elements (joints,
actuation, links, legs), the joint idealization, or the reading itself (clearance, dial misalignment).

:class:`AnalyticalChainModel` is the compliance-chain model of seed 000 (``femcheck.chain.evaluate``).
The device FE with contact joints plugs in through the same ``tcp_displacement`` signature
(:class:`femcheck.diagnose.fe_model.DeviceFEReadingModel`, nominal model only).
"""
from __future__ import annotations

import dataclasses
from typing import Protocol

import numpy as np

from femcheck.chain import ELEMENTS, MODEL_ELEMENTS, ChainAdjustments, evaluate
from femcheck.diagnose.working_state import WorkingState

#: element column indices in ``element_scale`` (order ``femcheck.chain.ELEMENTS``)
LG, ACT, SP, PROX, UJ = (ELEMENTS.index(e) for e in ("lg", "act", "sp", "prox", "uj"))


class ReadingModel(Protocol):
    """What a diagnosis needs from a stiffness model (analytical chain or device FE)."""

    name: str
    joints: str
    case: object

    @property
    def base_scale(self) -> np.ndarray:
        """(6, 5) element compliance scales of the model as given (1 = modelled, 0 = absent)."""

    def tcp_displacement(self, pose: np.ndarray, force: np.ndarray, element_scale: np.ndarray,
                         joint_rotation_compliance: float) -> np.ndarray:
        """(m, 3) TCP translation (m) under TCP forces ``force`` (m, 3) N at ``pose`` (m, 6)."""


@dataclasses.dataclass(frozen=True)
class AnalyticalChainModel:
    """Seed 000 compliance chain (``femcheck.chain.evaluate``) as a reading model.

    ``level`` "simplified" (guideways + proximal links) or "detailed" (+ actuation, spherical and universal
    joints, Hertz contacts linearized at each reading's load); ``joints`` "rigid" | "released".
    Always evaluated as the detailed chain with the absent elements' compliance scaled to 0, so that an
    effect can add a missing element back (``element_scale`` > 0).
    """

    case: object
    level: str = "detailed"
    joints: str = "rigid"

    @property
    def name(self) -> str:
        return f"analytical {self.level} ({self.joints} joints)"

    @property
    def base_scale(self) -> np.ndarray:
        return np.broadcast_to(np.array([e in MODEL_ELEMENTS[self.level] for e in ELEMENTS], float), (6, 5))

    def tcp_displacement(self, pose, force, element_scale, joint_rotation_compliance=0.0):
        pose = np.asarray(pose, float)
        W = np.zeros((len(pose), 6))
        W[:, :3] = force
        r = evaluate(self.case, pose, W, model="detailed", joints=self.joints, legs=_leg_geometry(self.case, pose),
                     adjust=ChainAdjustments(element_scale=element_scale, joint_rotation_compliance=joint_rotation_compliance))
        return r.twist[:, :3]

    def tcp_stiffness(self, pose, force, element_scale=None, joint_rotation_compliance=0.0):
        """(m, 6, 6) TCP stiffness (SI), contacts linearized at ``force`` (m, 3) N (for the seed 001 baseline)."""
        pose = np.asarray(pose, float)
        W = np.zeros((len(pose), 6))
        W[:, :3] = force
        scale = self.base_scale if element_scale is None else element_scale
        r = evaluate(self.case, pose, W, model="detailed", joints=self.joints,
                     adjust=ChainAdjustments(element_scale=scale, joint_rotation_compliance=joint_rotation_compliance))
        return r.K


_LEGS_CACHE: dict = {}


def _leg_geometry(case, pose: np.ndarray):
    """Inverse kinematics of ``pose`` (m, 6), cached: a fit evaluates the model hundreds of times at the same poses
    (the readings'), and the kinematics does not depend on the fitted parameters."""
    from femcheck.kinematics.psu6 import leg_geometry
    key = (id(case), pose.shape, pose.tobytes())
    legs = _LEGS_CACHE.get(key)
    if legs is None or legs[0] is not case:
        if len(_LEGS_CACHE) >= 16:
            _LEGS_CACHE.pop(next(iter(_LEGS_CACHE)))
        legs = _LEGS_CACHE[key] = (case, leg_geometry(case, pose))
    return legs[1]


def predict_readings(model: ReadingModel, readings, effects=(), values=()) -> np.ndarray:
    """(m, 3) predicted mean reading of every state of ``readings`` with ``effects`` (sequence of Effect)
    at parameter ``values`` (sequence of (k_e,) arrays, natural units), applied in stage order."""
    m = len(readings.phase)
    st = WorkingState(force=np.array(readings.force, float), scale=np.array(np.broadcast_to(model.base_scale, (m, 6, 5))),
                      c_rot=0.0, extra=np.zeros((m, 3)), sensor=np.eye(3))
    from femcheck.diagnose.extended_case import case_reading_effects
    held = case_reading_effects(model.case)     # a corrected case's [model.reading] effects come first at each stage
    for eff, v in sorted(held + list(zip(effects, values)), key=lambda ev: ev[0].stage):
        eff.apply(model, readings, np.asarray(v, float), st)
    d = model.tcp_displacement(readings.pose, st.force, st.scale, st.c_rot) + st.extra
    return d @ st.sensor.T
