"""The device FE model with contact joints as a reading model (FE-backed diagnosis).

Wraps the point models of a finished FE run (:func:`femcheck.verify.fe.run_fe`: solid guideway and link
super-elements at each test point) and predicts the TCP translation of a reading by solving the
detailed level with the chosen joints (default ``contact``: frictional ball-in-seat and pin-in-bore
joints, :mod:`femcheck.fe_device.joint_friction`) under that reading's TCP force, exactly as
``femcheck verify`` does (:func:`femcheck.fe_device.loads.solve_state`). Every reading is a monotonic
load from zero along its direction, which is the load path the secant contact-joint law is exact for;
the unload readings are therefore those of the loading branch (the joint law has no frictional
hysteresis on unloading — a limitation stated in docs/diagnose.md).

It is a *data source* (virtual experiments from FE, ``femcheck experiment simulate --model fe``) and can
be checked against data; it does not take effect parameters: a non-nominal ``element_scale`` or a joint
rotation compliance raises, since refitting an FE model per trial parameter is not what it is for.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.chain.haptic_6psu_model import MODEL_ELEMENTS
from femcheck.chain import ELEMENTS


@dataclasses.dataclass(frozen=True)
class DeviceFEReadingModel:
    """Reading model backed by the device FE (see module doc). ``fe``: a ``FEVerification`` with the
    detailed level; ``friction``: the joint friction data its contact joints used (None = the FE run's, else the
    case's). The joint laws are the FE run's (``fe.joint_laws``)."""

    case: object
    fe: object
    joints: str = "contact"
    friction: object = None
    level: str = "detailed"

    @property
    def name(self) -> str:
        return f"device FE, detailed level ({self.joints} joints, mesh {self.fe.mesh.level})"

    @property
    def base_scale(self) -> np.ndarray:
        return np.broadcast_to(np.array([e in MODEL_ELEMENTS["detailed"] for e in ELEMENTS], float), (6, 5))

    def _point_of(self, pose: np.ndarray) -> list[str]:
        from femcheck.errors import FemcheckError
        from femcheck.kinematics.psu6 import POINT_LABELS, test_points
        P = test_points(self.case)
        d = np.linalg.norm(pose[:, None, :3] - P[None, :, :3], axis=-1)
        k = np.argmin(d, axis=1)
        bad = np.flatnonzero(d[np.arange(len(k)), k] > 1e-9)
        if bad.size:
            raise FemcheckError(f"{self.name}: pose {pose[bad[0]].tolist()} is not a test point P0..P8; the FE "
                                "reading model has super-elements at the test points only")
        labels = [POINT_LABELS[i] for i in k]
        missing = sorted(set(labels) - set(self.fe.points))
        if missing:
            raise FemcheckError(f"{self.name}: no FE model at {', '.join(missing)} (run the FE at those points)")
        return labels

    def tcp_displacement(self, pose, force, element_scale, joint_rotation_compliance=0.0) -> np.ndarray:
        """(m, 3) TCP translation (m) under TCP forces ``force`` (m, 3) N at test-point poses (m, 6)."""
        from femcheck.fe_device.contact_scales import device_springs
        from femcheck.fe_device.joint_friction import joint_friction
        from femcheck.fe_device.device_model import actuation_at
        from femcheck.fe_device.loads import solve_state
        if not np.allclose(element_scale, self.base_scale) or joint_rotation_compliance != 0.0:
            raise ValueError(f"{self.name} evaluates the nominal FE model only (no effect parameters)")
        pose, force = np.asarray(pose, float), np.asarray(force, float)
        labels = self._point_of(pose)
        params = device_springs(self.case)
        friction = self.friction or getattr(self.fe, "friction", None) or joint_friction(self.case)
        out = np.zeros((len(pose), 3))
        # one nonlinear device solve per distinct (point, force); a zero force reads zero
        keys = {}
        for i, (p, f) in enumerate(zip(labels, force)):
            keys.setdefault((p, tuple(np.round(f, 12))), []).append(i)
        for (p, f), rows in keys.items():
            f = np.asarray(f)
            if not np.any(f):
                continue
            m = self.fe.models[p]
            k_act, K_lg = actuation_at(self.case, m)
            if self.level != "detailed":   # the simplified level has no actuation element, no cable across the rail
                K_lg = m.K_lg
            s = solve_state(K_lg, m.link.K, m.R_A, m.R_B, m.G, np.r_[f, 0.0, 0.0, 0.0], self.level, self.joints,
                            params, friction, k_act, getattr(self.fe, "joint_laws", None))
            out[rows] = s.twist[:3]
        return out


def device_fe_reading_model(case, points, mesh: str = "coarse", kind: str = "solid", joint_mesh: str = "coarse",
                            progress=None) -> DeviceFEReadingModel:
    """The device FE of ``femcheck verify`` with its joint FE (:func:`femcheck.verify.fe.contact_joint_inputs`:
    measured tilt slip ratio and contact-FE joint laws at ``joint_mesh``) at ``points``, detailed level, as a
    reading model (``femcheck experiment simulate --model fe``)."""
    from femcheck.verify.fe import contact_joint_inputs, run_fe
    cj = contact_joint_inputs(case, joint_mesh, progress)
    fe = run_fe(case, points, ("detailed",), mesh, jobs=1, kind=kind, progress=progress, friction=cj.friction,
                joint_laws=cj.joint_laws)
    return DeviceFEReadingModel(case, fe)
