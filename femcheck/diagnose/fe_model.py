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

from femcheck.chain import ELEMENTS, MODEL_ELEMENTS


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


#: load magnitudes (N) of the idealization-gap table of :class:`FEAnchoredChainModel` (0 reads 0; holds the
#: protocol's 5 N preload, 20 N total and its 5-30 N sweep exactly)
GAP_LOADS_N = np.arange(0.0, 35.01, 2.5)


@dataclasses.dataclass(frozen=True)
class FEAnchoredChainModel:
    """The analytical chain moved onto the device FE of the **unmodified** case: a reading model whose prediction
    is the chain's with the effect parameters plus the idealization gap of the case,

        δ(pose, F; θ) = δ_chain(pose, F; θ) + [δ_FE(pose, F) − δ_chain(pose, F; θ₀)],

    θ₀ the nominal parameters (``chain.base_scale``, no joint rotation compliance). At θ₀ it reads exactly what the
    device FE of the case reads (contact joints with friction and Hertz nonlinearity, solid parts), so data from
    the case's own FE are explained with no cause, and a cause's effect is the chain's change of the deflection
    (the effects scale the chain's element laws). ``device``: anything with ``tcp_displacement(pose, force)``
    (m, 3) of the unmodified case, e.g. :class:`femcheck.experiment.device_fe_world.DeviceFEWorld.of(case)`;
    it knows the case only, never the world the data come from. The gap is evaluated once per (poses, forces)
    array and kept (a fit calls the model hundreds of times at the readings' states).

    ``pin_laws`` (a :class:`femcheck.diagnose.pin_law.PinLawTable` of the case, optional): the U joint is then the
    device FE's own, nonlinear over its pin. The U-joint column of the element scales is the pin's bending compliance
    factor X (ρ^-4 for a pin of radius ρ r), and the chain's U joint of leg i at reading n takes the extra axial
    deflection e(|f_ni|; X_ni) of the contact-FE laws at its link force f_ni (released statics,
    :func:`~femcheck.diagnose.pin_law.link_forces`) as its secant, e / |f| on the joint's axial compliance. Without
    it (or on a chain without a U joint) the column scales the chain's linear U-joint law."""

    chain: object
    device: object
    pin_laws: object = None
    _gap: dict = dataclasses.field(default_factory=dict, compare=False, repr=False)

    @property
    def case(self):
        return self.chain.case

    @property
    def joints(self) -> str:
        return self.chain.joints

    @property
    def level(self) -> str:
        return self.chain.level

    @property
    def name(self) -> str:
        return f"{self.chain.name} + idealization gap to the {self.device.name}"

    @property
    def base_scale(self) -> np.ndarray:
        return self.chain.base_scale

    @classmethod
    def nearest(cls, case, device, pose, force, level: str = "detailed", pin_laws=None) -> "FEAnchoredChainModel":
        """Anchored on the chain of ``case`` (rigid or released joints) whose deflections at the states ``pose``
        (m, 6), ``force`` (m, 3) are nearer (RMS) to the ``device``'s: the joints the device FE behaves like (its
        frictional contact joints slip at the test loads: released), so that a cause moves the chain the way it
        moves the FE. Decided from the case and its FE alone."""
        from femcheck.diagnose import AnalyticalChainModel
        fe = device.tcp_displacement(pose, force)
        chains = [AnalyticalChainModel(case, level, j) for j in ("rigid", "released")]
        rms = [float(np.sqrt(np.mean((c.tcp_displacement(pose, force, c.base_scale) - fe) ** 2))) for c in chains]
        return cls(chains[int(np.argmin(rms))], device, pin_laws)

    def gap(self, pose, force) -> np.ndarray:
        """(m, 3) m: δ_FE − δ_chain at the nominal parameters.

        Tabulated per (pose, load direction) over the load magnitudes :data:`GAP_LOADS_N` (one device solve per
        level, once) and interpolated linearly in the magnitude: the readings' own loads (0, 5, ..., 30 N) are
        table levels, and the one cause that changes the deflecting force (``friction_hysteresis``) moves it
        along its direction by a fitted amount, which would otherwise need a device solve per trial value. A
        magnitude beyond the table is solved as it comes."""
        pose, force = np.asarray(pose, float), np.asarray(force, float)
        key = (pose.tobytes(), force.tobytes())
        hit = self._gap.get(key)
        if hit is not None:
            return hit
        F = np.linalg.norm(force, axis=1)
        unit = np.divide(force, F[:, None], out=np.zeros_like(force), where=F[:, None] > 0)
        out = np.zeros((len(pose), 3))
        tables = self._gap.setdefault("tables", {})
        groups: dict = {}
        for i in np.flatnonzero(F > 0):
            groups.setdefault(pose[i].tobytes() + np.round(unit[i], 12).tobytes(), []).append(i)
        for k, rows in groups.items():
            rows = np.asarray(rows)
            p, u = pose[rows[0]], unit[rows[0]]
            if k not in tables:
                tables[k] = self._solve_gap(np.repeat(p[None], len(GAP_LOADS_N), 0), np.outer(GAP_LOADS_N, u))
            beyond = F[rows] > GAP_LOADS_N[-1]
            out[rows] = np.stack([np.interp(F[rows], GAP_LOADS_N, tables[k][:, c]) for c in range(3)], axis=1)
            if beyond.any():
                b = rows[beyond]
                out[b] = self._solve_gap(pose[b], force[b])
        if len(self._gap) >= 64:
            self._gap.pop(next(k for k in self._gap if k not in ("tables", "uj_axial")))
        self._gap[key] = out
        return out

    def _solve_gap(self, pose, force) -> np.ndarray:
        return (self.device.tcp_displacement(pose, force)
                - self.chain.tcp_displacement(pose, force, self.chain.base_scale))

    def tcp_displacement(self, pose, force, element_scale, joint_rotation_compliance=0.0) -> np.ndarray:
        element_scale = self._pin_scale(pose, force, element_scale)
        return (self.chain.tcp_displacement(pose, force, element_scale, joint_rotation_compliance)
                + self.gap(pose, force))

    def _pin_scale(self, pose, force, element_scale) -> np.ndarray:
        """``element_scale`` with the U-joint column read as the pin's bending compliance factor (class doc): (m, 6, 5)
        chain scales whose U-joint column puts the contact-FE extra deflection e(|f|; X) on the chain's axial U-joint
        compliance c = 1/K_UC + 1/K_UB as the secant 1 + e / (|f| c)."""
        from femcheck.diagnose.model import UJ
        base = np.asarray(self.chain.base_scale, float)
        if self.pin_laws is None or base[0, UJ] == 0.0:
            return element_scale
        from femcheck.chain import device_parameters
        from femcheck.diagnose.pin_law import link_forces
        pose, force = np.asarray(pose, float), np.asarray(force, float)
        scale = np.array(np.broadcast_to(element_scale, (len(pose), 6, 5)), float)
        key = ("links", pose.tobytes(), force.tobytes())
        f = self._gap.get(key)
        if f is None:
            f = self._gap[key] = np.abs(link_forces(self.case, pose, force))
        p = self._gap.get("uj_axial")
        if p is None:
            q = device_parameters(self.case)
            p = self._gap["uj_axial"] = (float(np.squeeze(q.c_uc + q.c_ub)), float(np.squeeze(q.F_min_sp)))
        c, F_min = p
        # the device FE's own floor: below F_min a joint keeps its secant at F_min (fe_device.loads)
        F = np.maximum(f, F_min)
        scale[:, :, UJ] = 1.0 + self.pin_laws.extra_approach(F, scale[:, :, UJ]) / (F * c)
        return scale

    def tcp_stiffness(self, pose, force, element_scale=None, joint_rotation_compliance=0.0):
        """The chain's TCP stiffness (the seed 001 baseline's; the gap is a fixed offset, not a stiffness)."""
        return self.chain.tcp_stiffness(pose, force, element_scale, joint_rotation_compliance)
