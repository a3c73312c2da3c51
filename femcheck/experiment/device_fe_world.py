"""A physical world for the 6-PSU diagnosis: the device FE of a device whose legs may be built from changed cases.

The world is the detailed device FE of ``femcheck verify`` (:func:`femcheck.fe_device.loads.solve_state`: solid
guideway and proximal-link super-elements, the actuation as finite elements, frictional ``contact`` joints with
their contact-FE-measured laws), with one difference: **leg i is built from its own case** ``leg_cases[i]``. A
change of one leg (a thinner guideway bar, a tube of another alloy, thinner U-joint pins, a softer cable) is that
leg's case with the changed value; a change of every leg is the changed case in all six. Per leg and test point:

- guideway: the solid cantilever of the leg's case at that leg's slider length (:func:`.parts.guideway_element`);
- proximal link: the solid tube of the leg's case (:func:`.parts.link_element`), in the leg's frame;
- actuation: the axial and transverse cable springs of the leg's case (:func:`.actuation_fe.actuation_legs`);
- joints: the contact-FE law of the leg's ball and U joint (:func:`.joint_laws.measure_joint_law`), and the
  frictional slip moments of the leg's case (:func:`.joint_friction.joint_friction`, e.g. μ F r_pin with the
  leg's pin radius; the fields become per-leg arrays, which the friction law broadcasts over the six legs).

The geometry (clamps, sliders, link length, platform) is the reference case's: a change that moves it is not a
world of this module (refused). Every super-element and joint law is cached in the process by the inputs it reads
(the guideway's section, material and length; the tube's; a joint's own section, its materials and its solid
model), so legs and worlds that share a part share its solve, and a joint whose inputs did not change is the
reference's law (the on-disk joint-law cache is then hit by the reference case's key).

Readings: :meth:`DeviceFEWorld.tcp_displacement` (m, 3) under TCP forces at test points P0..P8, one nonlinear
device solve per distinct (point, force), loading branch (the joint law is the secant of a monotonic load, as in
:mod:`femcheck.diagnose.fe_model`). Mesh: ``mesh`` of the solid parts ("coarse" for the bench), ``joint_mesh`` of
the joint contact FE; ``joint_fe`` False uses the closed-form joint springs (frictional joints still), a tuple
of joint types ("spherical", "universal") the contact-FE laws of those only.
"""
from __future__ import annotations

import dataclasses
import hashlib

import numpy as np

#: per-process caches, keyed by the inputs each part reads (module doc)
_PARTS: dict = {}
_LAWS: dict = {}
_POINTS: dict = {}


def _memo(store: dict, key, build):
    if key not in store:
        store[key] = build()
    return store[key]


def _geometry_key(case) -> str:
    return repr((case.geometry, case.workspace))


def _joint_inputs(case, joint: str) -> str:
    """What the contact FE of ``joint`` reads: its own section (with its materials), its solid model, the mesh
    settings and the load ladder's geometry (the ladder is the released statics of the geometry)."""
    section = case.spherical_joint if joint == "spherical" else case.universal_joint
    return repr((joint, section, getattr(case.solid, f"{joint}_joint"), case.solid.mesh, _geometry_key(case)))


@dataclasses.dataclass(frozen=True)
class DeviceFEWorld:
    """The device FE with leg i built from ``leg_cases[i]`` (module doc). ``reference``: the case whose geometry,
    loads and measurement the world shares; ``tilt_slip_ratio``: ρ of the ball's friction moment (None = measured
    by the ball-tilt contact FE of the reference, as ``verify`` does; 1 = the closed form)."""

    reference: object
    leg_cases: tuple
    mesh: str = "coarse"
    joint_mesh: str = "coarse"
    kind: str = "solid"
    joint_fe: bool | tuple = True
    tilt_slip_ratio: float | None = None

    def __post_init__(self):
        if len(self.leg_cases) != 6:
            raise ValueError(f"a 6-PSU world needs 6 leg cases, got {len(self.leg_cases)}")
        g = _geometry_key(self.reference)
        for i, c in enumerate(self.leg_cases):
            if _geometry_key(c) != g:
                raise ValueError(f"leg {i}: its case changes the device geometry; a world of changed legs keeps "
                                 "the reference geometry")
        closed = [j for j in ("spherical", "universal") if j not in self._measured]
        if any(len({repr(getattr(c, f"{j}_joint")) for c in self.leg_cases}) > 1 for j in closed):
            raise ValueError("closed-form joint springs are one per device: legs with different joints need "
                             "joint_fe=True")

    @property
    def _measured(self) -> tuple:
        """The joint types that take their contact-FE law (``joint_fe``: True = both, False = none, or a tuple)."""
        if isinstance(self.joint_fe, bool):
            return ("spherical", "universal") if self.joint_fe else ()
        return tuple(self.joint_fe)

    @classmethod
    def of(cls, case, **kw) -> "DeviceFEWorld":
        """The unchanged device: every leg is ``case``."""
        return cls(case, (case,) * 6, **kw)

    @property
    def name(self) -> str:
        laws = (f"contact-FE laws of the {' and '.join(self._measured)} joints" if self._measured
                else "closed-form joint springs")
        return f"device FE, detailed level (frictional contact joints, {laws}, {self.kind} parts, mesh {self.mesh})"

    # ---- parts, each cached by the inputs it reads
    def _sizes(self):
        from femcheck.fe_device.mesh_levels import mesh_sizes
        return mesh_sizes(self.reference, self.mesh)

    def _guideway(self, case, length_m: float):
        from femcheck.fe_device.parts import guideway_element
        size = self._sizes().guideway_m
        key = ("guideway", repr(case.guideway), repr(case.model.beam_shear), repr(case.solid.mesh),
               round(float(length_m), 12), self.kind, size)
        return _memo(_PARTS, key, lambda: guideway_element(case, float(length_m), self.kind, size))

    def _link(self, case):
        from femcheck.fe_device.parts import link_element
        size = self._sizes().link_m
        key = ("link", repr(case.proximal_link), repr(case.model.beam_shear), repr(case.solid.mesh),
               float(case.geometry.proximal_link_length_m), self.kind, size)
        return _memo(_PARTS, key, lambda: link_element(case, self.kind, size))

    def _law(self, case, joint: str):
        """The contact-FE law of ``joint`` of ``case``; the reference's when the joint's inputs are its."""
        from femcheck.fe_device.joint_laws import measure_joint_law
        own = _joint_inputs(case, joint)
        source = self.reference if own == _joint_inputs(self.reference, joint) else case
        return _memo(_LAWS, (own, self.joint_mesh), lambda: measure_joint_law(source, joint, self.joint_mesh))

    def _ratio(self) -> float:
        if self.tilt_slip_ratio is not None:
            return float(self.tilt_slip_ratio)
        from femcheck.verify.contact_joints import ball_tilt_study, tilt_slip_ratio
        key = ("tilt", _joint_inputs(self.reference, "spherical"))
        return _memo(_LAWS, key, lambda: tilt_slip_ratio(ball_tilt_study(self.reference)))

    def _joints(self):
        """(joint_laws, friction, springs) of the six legs."""
        from femcheck.fe_device.contact_scales import device_springs
        from femcheck.fe_device.joint_friction import joint_friction
        rho = self._ratio()
        fr = [joint_friction(c, tilt_slip_ratio=rho) for c in self.leg_cases]
        fields = {f.name: (np.array([getattr(x, f.name) for x in fr]) if len({getattr(x, f.name) for x in fr}) > 1
                           else getattr(fr[0], f.name)) for f in dataclasses.fields(fr[0])}
        friction = dataclasses.replace(fr[0], **fields)
        # the closed-form springs only fill in where the FE has no law of its own (one per device: __post_init__)
        springs = device_springs(self.leg_cases[0])
        if not self._measured:
            return None, friction, springs
        from femcheck.fe_device.joint_laws import JointLaws
        laws = {j: LegJointLaws(tuple(self._law(c, j) for c in self.leg_cases)) for j in self._measured}
        return JointLaws(**laws), friction, springs

    def _point(self, label: str):
        """Everything the device solve of point ``label`` needs (cached per world and point)."""
        def build():
            from femcheck.fe_device.actuation_fe import actuation_legs
            from femcheck.fe_device.device_model import point_model
            from femcheck.kinematics.points import point_set
            legs = point_set(self.reference, (label,)).legs
            s = legs.slider[0]
            guides = [self._guideway(c, s[i]) for i, c in enumerate(self.leg_cases)]
            m = point_model(self.reference, legs, 0, label, guides, self._link(self.reference))
            K_link = np.stack([self._link(c).K for c in self.leg_cases])
            e = np.asarray(self.reference.geometry.guideway_direction, float)
            e = e / np.linalg.norm(e)
            lengths = (m.B - m.A) @ e
            k_act, k_t = np.zeros(6), np.zeros(6)
            for i, c in enumerate(self.leg_cases):   # each leg's cable from its own case (6 legs, not poses)
                if c.actuation.fe.model != "elements":
                    raise ValueError(f"leg {i}: the world needs the actuation FE ([actuation.fe] model = \"elements\")")
                a, t = actuation_legs(c, lengths[i:i + 1], e)
                k_act[i], k_t[i] = a[0], t[0]
            K_lg = m.K_lg.copy()
            K_lg[:, 0, 0] += k_t   # the cable pretension across the rail (femcheck.fe_device.device_model.actuation_at)
            K_lg[:, 1, 1] += k_t
            return m, K_link, K_lg, k_act
        legs_key = hashlib.sha256(repr((self.leg_cases, self.mesh, self.kind)).encode()).hexdigest()
        return _memo(_POINTS, (legs_key, label), build)

    def tcp_displacement(self, pose, force) -> np.ndarray:
        """(m, 3) TCP translation (m) under TCP forces ``force`` (m, 3) N at test-point poses ``pose`` (m, 6)."""
        from femcheck.fe_device.loads import solve_state
        from femcheck.kinematics.psu6 import POINT_LABELS, test_points
        pose, force = np.asarray(pose, float), np.asarray(force, float)
        P = test_points(self.reference)
        d = np.linalg.norm(pose[:, None, :3] - P[None, :, :3], axis=-1)
        k = np.argmin(d, axis=1)
        if np.any(d[np.arange(len(k)), k] > 1e-9):
            raise ValueError(f"{self.name}: readings must be at the test points P0..P8")
        laws, friction, springs = self._joints()
        out = np.zeros((len(pose), 3))
        keys: dict = {}
        for i, (p, f) in enumerate(zip(k, force)):   # one device solve per distinct (point, force)
            keys.setdefault((int(p), tuple(np.round(f, 12))), []).append(i)
        for (p, f), rows in keys.items():
            if not np.any(f):
                continue
            m, K_link, K_lg, k_act = self._point(POINT_LABELS[p])
            s = solve_state(K_lg, K_link, m.R_A, m.R_B, m.G, np.r_[f, 0.0, 0.0, 0.0], "detailed", "contact",
                            springs, friction, k_act, laws)
            out[rows] = s.twist[:3]
        return out


@dataclasses.dataclass(frozen=True)
class LegJointLaws:
    """Six legs' measured laws of one joint type, read as one law by the device solve (its leg forces F are (6,)):
    leg i's law answers for leg i. Legs sharing a law object are evaluated once."""

    laws: tuple

    def _per_leg(self, method: str, F) -> np.ndarray:
        F = np.asarray(F, float)
        out = None
        for law in {id(x): x for x in self.laws}.values():
            legs = [i for i, x in enumerate(self.laws) if x is law]
            v = getattr(law, method)(F[legs])
            if out is None:
                out = np.empty(F.shape + v.shape[1:])
            out[legs] = v
        return out

    def secant(self, F) -> np.ndarray:
        return self._per_leg("secant", F)

    def component_stiffness(self, F) -> np.ndarray:
        return self._per_leg("component_stiffness", F)
