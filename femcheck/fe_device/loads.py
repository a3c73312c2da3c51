"""Load protocol of the device FE model (seed 000 §4.2 and eq. 1; docs/conventions.md §8-9).

* simplified level: the test load P_T (50 N) along +x, +y or +z at the TCP; the model is linear, so the
  deflection is the response to P_T alone (the 15 N preload of the experiment cancels in eq. 1).
* detailed level: preload P_p (5 N), then P_p + P_T (20 N); deflection δ = t(P_p + P_T) − t(P_p) (eq. 1).
  The spherical joints are nonlinear Hertz springs, F = (4/3) E* √R* δ^{3/2} (Johnson 1985 eq. 4.23,
  docs/conventions.md §5), isotropic as in the analytical model. Each load state is solved exactly by a
  fixed point on the secant stiffness k_i = F_i / δ(F_i) of each joint, F_i = max(|f_i|, F_min) the force
  its leg transmits (the secant of a nonlinear elastic spring reproduces its force at that state):
  start from the tangent stiffness at F_min, iterate until the largest relative change of k is < 1e-10.
  Actuation (1/c_act of eq. 44, or with ``[actuation.fe] model = "elements"`` the condensed shaft + capstan +
  cable FE of :mod:`.actuation_fe`) and the U-joint (K_UC, K_UB) springs are linear.
* detailed level, ``contact`` joints: the same, plus the frictional rotation springs of the joints
  (:mod:`.joint_friction`, secant stiffness min(k_stick, M_slip(F_i) / |r|)) in the same fixed point;
  each of the two load states is reached by monotonic proportional loading from zero, which is what
  makes the secant (deformation-theory) form of the stick/slip law exact (see that module).

The analytical detailed model instead uses the *tangent* stiffness at the force of the test load alone
(docs/conventions.md §6); the two differ in the spherical-joint term only (measured in docs/verify.md).
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np

from femcheck.errors import ConvergenceError
from femcheck.fe_device.joints import joint_layout
from femcheck.kinematics.directions import direction_unit as _direction_unit
from femcheck.fe_device.leg_model import condense_legs
from femcheck.fe_device.substructure import solve_platform

log = logging.getLogger(__name__)

FIXED_POINT_RTOL = 1e-10
MAX_ITERATIONS = 200
#: plain iterations before the fixed point may be extrapolated (a state that converges fast is never touched)
ACCEL_AFTER = 10
#: Aitken extrapolation only for slow *monotone* linear convergence: a contraction ratio of consecutive changes in
#: (ACCEL_RATIO, ACCEL_RATIO_MAX) along one direction (cosine of consecutive changes above ACCEL_COSINE)
ACCEL_RATIO = 0.5
ACCEL_RATIO_MAX = 0.999
ACCEL_COSINE = 0.99


def direction_unit(direction: str) -> np.ndarray:
    """'+x' -> (1, 0, 0), '-z' -> (0, 0, -1) (signed form only; :mod:`femcheck.kinematics.directions`)."""
    return _direction_unit(direction, sign_required=True)


def hertz_approach(F, E_star, R_star):
    """δ(F) = (3 F / (4 E* √R*))^{2/3} (m) of a Hertz point contact under F (N) (Johnson eq. 4.23)."""
    return (3.0 * np.asarray(F, float) / (4.0 * E_star * np.sqrt(R_star))) ** (2.0 / 3.0)


class _AitkenSecant:
    """Safeguarded Aitken Δ² extrapolation of the secant fixed point x_{n+1} = g(x_n) (x: every spring, flattened).

    Why: a slipping frictional rotation spring has the secant k = M_s / |r(k)|; where that spring carries most of
    the compliance along its rotation path, r ~ M / k and the map k -> M_s / |r(k)| is close to the identity: the
    plain iteration converges linearly with a contraction ratio ρ close to 1 (0.92 measured for a pin axis of a leg
    with glass-fibre polyamide tubes: 250 iterations to 1e-10). For such a mode the error after a plain step is
    d ρ / (1 - ρ) with d the step, ρ the ratio of consecutive steps (Aitken), so the iterate jumps there. Safeguards:
    only after ``ACCEL_AFTER`` plain iterations, only when two consecutive steps point along one direction (cosine
    > ``ACCEL_COSINE``, relative components) with ``ACCEL_RATIO`` < ρ < ``ACCEL_RATIO_MAX``, never to a negative
    spring, two plain steps between extrapolations, and ``ACCEL_AFTER`` plain steps before the next one when the plain
    step after a jump is not smaller than the one before it (more than one slow mode, or a stick/slip switch: the
    jump did not help; the plain steps let the fast modes die out before the ratio is measured again). Convergence is still judged on a plain step, so the state
    returned is a fixed point of the secant law to the same tolerance."""

    def __init__(self):
        self.iteration, self.step, self.extrapolations, self.held_until = 0, None, 0, 0
        self.jumped_from = None   # the relative step size before the last extrapolation

    def __call__(self, x_old: np.ndarray, x_new: np.ndarray) -> np.ndarray:
        self.iteration += 1
        step = x_new - x_old
        prev, self.step = self.step, step
        size = float(np.max(np.abs(step) / np.maximum(np.maximum(np.abs(x_old), np.abs(x_new)), 1e-300)))
        if self.jumped_from is not None:
            # the first plain step after a jump must be smaller than the one before it, else the map is not one
            # linear mode here (two modes, a stick/slip switch): ACCEL_AFTER plain steps before the next jump
            if size >= self.jumped_from:
                self.held_until = self.iteration + ACCEL_AFTER
            self.jumped_from = None
        if prev is None or self.iteration <= max(ACCEL_AFTER, self.held_until):
            return x_new
        # both steps relative to one scale (springs of N/m and N m/rad side by side), the ratio then unbiased
        scale = np.maximum(np.abs(x_new), 1e-300)
        d, prev = step / scale, prev / scale
        pp, dp = float(prev @ prev), float(d @ prev)
        if pp == 0.0 or d @ d == 0.0:
            return x_new
        rho, cos = dp / pp, dp / np.sqrt(pp * float(d @ d))
        if not (ACCEL_RATIO < rho < ACCEL_RATIO_MAX and cos > ACCEL_COSINE):
            return x_new
        x = x_new + (x_new - x_old) * (rho / (1.0 - rho))
        if np.any(x < 0.0):
            return x_new
        self.step = None   # the next ratio is measured on two plain steps again
        self.extrapolations += 1
        self.jumped_from = size
        return x


def _relative_change(new, old) -> float:
    """max |new - old| / max(|new|, |old|) (0 where both vanish: a frictionless joint's zero spring)."""
    scale = np.maximum(np.abs(new), np.abs(old))
    return float(np.max(np.where(scale > 0, np.abs(new - old) / np.where(scale > 0, scale, 1.0), 0.0)))


@dataclasses.dataclass(frozen=True)
class LoadState:
    """Equilibrium of one point under one TCP wrench: ``twist`` (6,), ``u_C`` (6, 6) platform-point twists,
    ``leg_force`` (6,) N, ``k_sp`` (6,) N/m secant joint stiffness (NaN for the simplified level),
    ``iterations`` of the fixed point (1 if linear), ``legs`` the :class:`LegSolution`."""

    twist: np.ndarray
    u_C: np.ndarray
    leg_force: np.ndarray
    k_sp: np.ndarray
    iterations: int
    legs: object


def solve_state(K_lg, K_link, R_A, R_B, G, wrench, level: str, joints: str, params, friction=None,
                k_act=None, joint_laws=None) -> LoadState:
    """Equilibrium under ``wrench`` (6,) for 6 legs (K_lg (6, 6, 6), R_A, R_B (6, 3, 3), G (6, 6, 6)).

    ``params``: :class:`femcheck.fe_device.contact_scales.DeviceSprings`, the FE's own closed-form springs (ball
    Hertz spring, U joint line contact and pin bending, eq. 44 actuation) where the FE has no element or measured
    law of its own (never the analytical model's :class:`femcheck.chain.DeviceParameters`);
    ``friction``: :class:`femcheck.fe_device.joint_friction.JointFriction` (``contact`` joints only);
    ``k_act`` (6,) N/m: the actuation springs along the rails (default 1/c_act of eq. 44 from ``params``;
    :mod:`femcheck.fe_device.actuation_fe` gives them from elements);
    ``joint_laws``: :class:`femcheck.fe_device.joint_laws.JointLaws`, the contact-FE-measured law of each joint
    type that has one (ball: secant F / δ_FE(F); U joint: lateral stick tangent and axial secant; the stick
    rotational stiffnesses of ``contact`` joints), replacing the closed forms on the FE side; None: closed forms.
    """
    layout = joint_layout(level, joints)
    if level == "simplified":
        legs = condense_legs(K_lg, K_link, R_A, R_B, layout)
        t, uC = solve_platform(legs.K, G, wrench)
        f = np.linalg.norm(np.einsum("iab,ib->ia", legs.K, uC)[:, :3], axis=1)
        return LoadState(t, uC, f, np.full(6, np.nan), 1, legs)
    c_uc, c_ub = float(np.squeeze(params.c_uc)), float(np.squeeze(params.c_ub))
    k_act = np.full(6, 1.0 / float(np.squeeze(params.c_act))) if k_act is None else np.asarray(k_act, float)
    Es, Rs, Fmin = (float(np.squeeze(v)) for v in (params.E_star_sp, params.R_star_sp, params.F_min_sp))
    law_sp = law_uj = None
    if joint_laws is not None:
        law_sp, law_uj = joint_laws.spherical, joint_laws.universal

    def translation_springs(F):
        """(k_sp (6,) N/m isotropic, k_uj (6, 3) N/m in frame B) at the leg forces F (6,) N."""
        k_sp = law_sp.secant(F) if law_sp is not None else F / hertz_approach(F, Es, Rs)
        if law_uj is None:
            return k_sp, np.tile([1.0 / c_uc, 1.0 / c_uc, 1.0 / (c_uc + c_ub)], (6, 1))
        K = law_uj.component_stiffness(F)
        return k_sp, np.stack([K[:, 0], K[:, 1], law_uj.secant(F)], axis=1)

    def stick(F):
        """(k_tilt, k_spin, k_pin) (6,) N m/rad: measured where a law is, else the closed forms."""
        kt, ks, kp = friction.stick_stiffness(F)
        if law_sp is not None:
            K = law_sp.component_stiffness(F)
            kt, ks = 0.5 * (K[:, 3] + K[:, 4]), K[:, 5]
        if law_uj is not None:
            kp = law_uj.component_stiffness(F)[:, 3:5]
        return kt, ks, np.broadcast_to(np.asarray(kp).reshape(6, -1), (6, 2))

    F = np.full(6, Fmin)
    if law_sp is None:
        # the closed form starts from the Hertz tangent at F_min (bit-identical to the baselines)
        k_sp, k_uj = np.full(6, (6.0 * Es**2 * Rs * Fmin) ** (1.0 / 3.0)), translation_springs(F)[1]
    else:
        k_sp, k_uj = translation_springs(F)
    contact = joints == "contact"
    if contact:
        if friction is None:
            raise ValueError("contact joints need the joint friction data (femcheck.fe_device.joint_friction)")
        k_tilt, k_spin, k_pin = stick(F)   # start stuck, at F_min
        k_rot_sp = np.stack([k_tilt, k_tilt, k_spin], axis=1)
        k_rot_uj = np.array(k_pin)

    def springs(k_sp, k_uj):
        if not contact:
            return k_sp, k_uj
        return (np.hstack([np.repeat(k_sp[:, None], 3, axis=1), k_rot_sp]), np.hstack([k_uj, k_rot_uj]))

    accelerate = _AitkenSecant()
    for it in range(1, MAX_ITERATIONS + 1):
        ks, ku = springs(k_sp, k_uj)
        legs = condense_legs(K_lg, K_link, R_A, R_B, layout, k_act=k_act, k_sp=ks, k_uj=ku)
        t, uC = solve_platform(legs.K, G, wrench)
        f = np.linalg.norm(np.einsum("iab,ib->ia", legs.K, uC)[:, :3], axis=1)
        F = np.maximum(f, Fmin)
        k_new, kuj_new = translation_springs(F)
        change = max(float(np.max(np.abs(k_new - k_sp) / k_sp)), _relative_change(kuj_new, k_uj))
        old, new = [k_sp, k_uj], [k_new, kuj_new]
        if contact:
            q = legs.interior(uC)["q"]
            r_sp = q[:, legs.blocks["sp"]][:, 3:6]
            r_uj = q[:, legs.blocks["uj"]][:, 3:5]
            kt, ks_, kp = stick(F)
            new_sp, new_uj = friction.secant_stiffness(F, r_sp, r_uj, stick=(kt, ks_, kp))
            change = max(change, _relative_change(new_sp, k_rot_sp), _relative_change(new_uj, k_rot_uj))
            old, new = old + [k_rot_sp, k_rot_uj], new + [new_sp, new_uj]
        if change < FIXED_POINT_RTOL:
            k_sp, k_uj = k_new, kuj_new
            if contact:
                k_rot_sp, k_rot_uj = new_sp, new_uj
            ks, ku = springs(k_sp, k_uj)
            legs = condense_legs(K_lg, K_link, R_A, R_B, layout, k_act=k_act, k_sp=ks, k_uj=ku)
            t, uC = solve_platform(legs.K, G, wrench)
            return LoadState(t, uC, f, k_sp, it, legs)
        x = accelerate(np.concatenate([a.ravel() for a in old]), np.concatenate([a.ravel() for a in new]))
        parts = np.split(x, np.cumsum([a.size for a in new])[:-1])
        k_sp, k_uj = (p.reshape(a.shape) for p, a in zip(parts[:2], new))
        if contact:
            k_rot_sp, k_rot_uj = (p.reshape(a.shape) for p, a in zip(parts[2:], new[2:]))
    raise ConvergenceError(f"Hertz secant fixed point did not converge in {MAX_ITERATIONS} iterations "
                           f"(last relative change {change:.3g}, {accelerate.extrapolations} Aitken "
                           f"extrapolations)", [], {"k_sp": k_sp.tolist()})


@dataclasses.dataclass(frozen=True)
class LoadCaseResult:
    """One (level, joints, direction) load case: ``twist`` (6,) TCP deflection (m, rad) per eq. 1,
    ``deflection_m`` along the load, ``contributions`` (5,) element shares of the incremental strain
    energy (order lg, act, sp, prox, uj), ``iterations`` fixed-point iterations (total state),
    ``states``: the :class:`LoadState` s solved (preload first for the detailed level)."""

    level: str
    joints: str
    direction: str
    load_N: float
    twist: np.ndarray
    deflection_m: float
    contributions: np.ndarray
    iterations: int
    states: tuple


def load_case(case, K_lg, K_link, R_A, R_B, G, level: str, joints: str, direction: str, params,
              friction=None, k_act=None, joint_laws=None) -> LoadCaseResult:
    """Apply the protocol of ``level`` along ``direction`` and return the deflection (module docstring);
    ``k_act``, ``joint_laws``: see :func:`solve_state`."""
    d = direction_unit(direction)
    L = case.loads
    if level == "simplified":
        P = L.simplified_test_N
        s = solve_state(K_lg, K_link, R_A, R_B, G, np.r_[P * d, 0, 0, 0], level, joints, params)
        states, twist = (s,), s.twist
        inc = s.legs.interior(s.u_C)["energy"]
    else:
        P = L.detailed_test_N
        sp_ = solve_state(K_lg, K_link, R_A, R_B, G, np.r_[L.detailed_preload_N * d, 0, 0, 0], level, joints, params,
                          friction, k_act, joint_laws)
        st = solve_state(K_lg, K_link, R_A, R_B, G, np.r_[(L.detailed_preload_N + P) * d, 0, 0, 0], level, joints,
                         params, friction, k_act, joint_laws)
        states, twist = (sp_, st), st.twist - sp_.twist
        inc = st.legs.interior(st.u_C - sp_.u_C)["energy"]
    e = inc.sum(axis=0)
    return LoadCaseResult(level, joints, direction, P, twist, float(twist[:3] @ d), e / e.sum(),
                          states[-1].iterations, states)
