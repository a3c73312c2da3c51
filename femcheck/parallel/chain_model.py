"""General compliance-chain model of a parallel device, vectorized over poses.

Every leg is a serial chain from the base to its platform attachment C_i. Each element's compliance is
carried to C_i (frame U) and the elements of a leg add in series, as in the 6-PSU model:

- a link (tube or bar) is a cantilever clamped at its start joint and loaded at its end joint, of its
  current length (a P joint inside it makes the length vary), ``Jf(C - E)^T Rot S_cant Rot^T Jf(C - E)``;
- the drive of the actuated joint (detailed level): ``c xi xi^T`` with xi the joint's unit twist at C
  (a spring along the P axis, or about the R axis);
- joint contact laws (detailed level): Hertz point contact of an S joint (translational ``I3 / k(F)``,
  linearized at the force of its own leg under the wrench, fixed point) and Hertz line contact + pin
  bending of an R or U joint (translational, in the frame of the adjacent link);
- an FE-measured joint law (detailed level): the joint contact FE's 6 x 6 compliance at the joint centre J in the
  frame of the adjacent link, carried to C_i as a link is, ``Jf(C - J)^T Rot S_J Rot^T Jf(C - J)``; under
  ``released`` the leg's wrenches have no moment about the joint's free axes, so those rotation entries drop out;
  with a force ladder its axial entry is the tangent of the measured approach law at the joint's own axial force
  (:func:`ladder_compliance`, the same fixed point as the Hertz point contacts).

Joint idealizations: ``rigid`` (passive joints carry moments and forces: the leg is a welded chain,
``K_i = S_i^-1``) and ``released`` (passive freedoms free: the leg carries only wrenches reciprocal to them,
``K_i = N (N^T S_i N)^-1 N^T`` with N a basis of those wrenches; for a UPS leg N = [u; 0] and
``K_i = k_i g g^T``). The rigid platform sums the legs at the TCP: ``G_i = Jf(C_i - T)^T``,
``K_T = sum_i G_i^T K_i G_i``, ``t_T = K_T^-1 W_T``, ``W_C,i = K_i G_i t_T``.
"""
from __future__ import annotations

import dataclasses
import functools

import numpy as np

# the laws through their modules: the function a module holds when the model runs is the one used
from femcheck.compliance import cantilever_beam, hertz_point_contact
from femcheck.errors import ConvergenceError, UnreachablePoseError
from femcheck.kinematics.frames import rot6, twist_shift
from femcheck.parallel.leg_kinematics import DeviceState, as_poses, released_wrenches, solve_legs

MODELS = ("simplified", "detailed")
JOINT_IDEALIZATIONS = ("rigid", "released")
_FIXED_POINT_TOL = 1e-12
_FIXED_POINT_MAX_ITER = 200
#: a device with ladder laws: rounding of the joint forces in a rigid leg with a contact-FE 6 x 6 (stick
#: compliances up to 1e2 rad/(N m) next to 1e-6 m/N) keeps the fixed point at a few 1e-12, so such a device
#: converges to 1e-10 relative (its Hertz contacts too); devices without ladders keep _FIXED_POINT_TOL
_LADDER_TOL = 1e-10


@dataclasses.dataclass(frozen=True)
class TcpResult:
    """The TCP of a device model at n poses (SI): ``model`` and ``joints`` evaluated, poses (n, 6), wrench (n, 6);
    K, S (n, 6, 6) TCP stiffness and compliance (twist [d; theta] <- wrench [F; M]); twist (n, 6) under the wrench."""

    model: str
    joints: str
    poses: np.ndarray
    wrench: np.ndarray
    K: np.ndarray
    S: np.ndarray
    twist: np.ndarray

    def directional_stiffness(self, direction) -> np.ndarray:
        """(n,) stiffness along a unit translation ``direction`` (3,): 1 / (d^T S_tt d), N/m (seed 000 §4.7)."""
        from femcheck.compliance.directional import directional_stiffness
        return directional_stiffness(self.S, direction)


@dataclasses.dataclass(frozen=True)
class ParallelResult(TcpResult):
    """Result of :func:`evaluate` at n poses (SI): :class:`TcpResult` and leg_stiffness (n, L, 6, 6) K_i at C_i; leg_wrench (n, L, 6) W_C,i; element_names (E,); element_energy (n, L, E)
    W_C^T S_e W_C per leg and element kind (J, x2); contributions (n, E) share of each element kind (sums to 1;
    NaN at zero load); hertz_stiffness {(leg, joint): (n,)} N/m of the linearized Hertz point contacts and the
    axial tangent stiffness of the measured laws with a force ladder.
    """

    leg_stiffness: np.ndarray
    leg_wrench: np.ndarray
    element_names: tuple[str, ...]
    element_energy: np.ndarray
    contributions: np.ndarray
    hertz_stiffness: dict
    iterations: int
    #: the inverse kinematics (a DeviceState), or a function solving it on first use of :attr:`state` (the
    #: fused compiled path keeps no leg state)
    state_source: object = dataclasses.field(repr=False, compare=False)

    @functools.cached_property
    def state(self) -> DeviceState:
        """The inverse kinematics of ``poses`` (:func:`~femcheck.parallel.leg_kinematics.solve_legs`)."""
        src = self.state_source
        return src if isinstance(src, DeviceState) else src()


def ladder_compliance(F, loads_N, approach_m) -> np.ndarray:
    """Axial tangent compliance d delta / dF (m/N) of a measured force ladder at forces F (N, any shape).

    delta(F) is the piecewise power law through the ladder, delta = delta_k (F / F_k)^p_k with
    p_k = ln(delta_k+1 / delta_k) / ln(F_k+1 / F_k), continued beyond its ends
    (:meth:`femcheck.fe_device.joint_laws.MeasuredJointLaw.approach`), so d delta / dF = p_k delta(F) / F: exact for
    a Hertz contact (p = 2/3: the ``hertz_point`` tangent). F is floored at the ladder's first force (the contact
    stays closed, as ``min_contact_force_N``)."""
    lF, ld = np.log(np.asarray(loads_N, float)), np.log(np.asarray(approach_m, float))
    p = np.diff(ld) / np.diff(lF)
    x = np.log(np.maximum(np.asarray(F, float), loads_N[0]))
    k = np.clip(np.searchsorted(lF, x) - 1, 0, p.size - 1)
    return p[k] * np.exp(ld[k] + p[k] * (x - lF[k])) / np.exp(x)


def _measured_law_at_C(leg, s, joint, c_axial=None) -> np.ndarray:
    """(n, 6, 6) compliance of ``leg``'s measured law at ``joint`` carried to C (frame U); ``c_axial`` (n,): the
    axial entry of a ladder law, its row and column scaled by sqrt(c_axial / S_zz) (a congruence: stays definite)."""
    S_J, c, m = leg.measured_law[joint]
    n = s.C.shape[0]
    S = np.broadcast_to(S_J, (n, 6, 6))
    if c_axial is not None:
        d = np.ones((n, 6))
        d[:, 2] = np.sqrt(c_axial / S_J[2, 2])
        S = S * d[:, :, None] * d[:, None, :]
    Q = rot6(s.link_R[:, m])
    to_C = twist_shift(s.C - s.centres[:, c])
    return to_C @ Q @ S @ np.swapaxes(Q, -1, -2) @ np.swapaxes(to_C, -1, -2)


def leg_element_compliances(device, state: DeviceState, model: str = "detailed") -> list[dict[str, np.ndarray]]:
    """Per leg: {element name: (n, 6, 6) compliance carried to C_i, frame U}, without the Hertz point terms and the
    measured laws with a force ladder (load-dependent, added by :func:`evaluate`). Links of the same name in one
    leg add up."""
    out = []
    for i, leg in enumerate(device.legs):
        s = state.legs[i]
        n = s.C.shape[0]
        parts: dict[str, np.ndarray] = {}
        for m, ln in enumerate(leg.links):
            if ln.section is None:
                continue
            S_loc = cantilever_beam.cantilever_compliance(s.link_length[:, m], ln.E, ln.G, ln.section, device.beam_shear)
            Q = rot6(s.link_R[:, m])
            to_C = twist_shift(s.C - s.centres[:, ln.end])
            S_C = to_C @ Q @ S_loc @ np.swapaxes(Q, -1, -2) @ np.swapaxes(to_C, -1, -2)
            parts[ln.name] = parts.get(ln.name, 0.0) + S_C
        if model == "detailed":
            xi = s.twists[:, leg.actuated_dof, :]
            parts["drive"] = leg.drive_compliance * xi[:, :, None] * xi[:, None, :]
            if leg.hertz_line:
                S = np.zeros((n, 6, 6))
                for _, (c_uc, c_ub, m) in leg.hertz_line.items():
                    R = s.link_R[:, m]
                    S[:, :3, :3] += np.einsum("nij,j,nkj->nik", R, np.array([c_uc, c_uc, c_uc + c_ub]), R)
                parts["hertz_line"] = S
            if leg.measured_law:
                S = np.zeros((n, 6, 6))
                for j in leg.measured_law:
                    if j not in leg.measured_ladder:
                        S += _measured_law_at_C(leg, s, j)
                parts["measured_law"] = S
        out.append(parts)
    return out


def joint_rotation_compliances(device, state: DeviceState, c_rot: float) -> list[dict[str, np.ndarray]]:
    """Per leg: {element kind: (n, 6, 6)} the joint-rotation compliance ``c_rot`` (rad/(N m)) of its S and U joints
    carried to C_i, frame U: each passive joint rotation a torsional spring instead of a welded joint (rigid joints;
    the passive-joint elimination with springs instead of free joints). An S joint: ``c_rot I3`` on the rotations
    about its centre J; a U joint: ``c_rot (I3 - z z^T)``, its two rotations normal to the link z ending at it
    (docs/conventions.md §5). At C: ``Jf(C - J)^T [[0, 0], [0, S_rot]] Jf(C - J)``. The S terms belong to the
    ``hertz_point`` element kind, the U terms to ``hertz_line`` (the joints' contact laws; not scaled)."""
    return [_joint_rotations(leg, s, c_rot) for leg, s in zip(device.legs, state.legs)]


def _joint_rotations(leg, s, c_rot: float) -> dict[str, np.ndarray]:
    """:func:`joint_rotation_compliances` of one leg, ``s`` its LegState."""
    parts: dict[str, np.ndarray] = {}
    for k, jt in enumerate(leg.joint_types):
        if jt not in ("S", "U"):
            continue
        c = int(leg.joint_centre[k])
        S_J = np.zeros((s.C.shape[0], 6, 6))
        S_J[:, 3:, 3:] = c_rot * np.eye(3)
        if jt == "U":   # the link ending at the joint's centre c is link c - 1
            z = s.link_R[:, c - 1, :, 2]
            S_J[:, 3:, 3:] -= c_rot * z[:, :, None] * z[:, None, :]
        to_C = twist_shift(s.C - s.centres[:, c])
        kind = "hertz_point" if jt == "S" else "hertz_line"
        parts[kind] = parts.get(kind, 0.0) + to_C @ S_J @ np.swapaxes(to_C, -1, -2)
    return parts


def _leg_stiffness(S, N):
    """K = N (N^T S N)^-1 N^T, (n, 6, 6)."""
    A = np.swapaxes(N, -1, -2) @ S @ N
    K = N @ np.linalg.solve(A, np.swapaxes(N, -1, -2))
    return 0.5 * (K + np.swapaxes(K, -1, -2))


def evaluate(device, poses, wrench=None, *, model: str = "detailed", joints: str = "released",
             state: DeviceState | None = None, element_scale=None, backend: str = "compiled",
             joint_rotation_compliance: float = 0.0) -> ParallelResult:
    """Stiffness, deflection and element breakdown of ``device`` (:class:`~femcheck.parallel.device.ParallelDevice`).

    Parameters
    ----------
    poses : (n, 6) float, TCP poses [x, y, z, rx, ry, rz] (m, rad; rotation vector)
    wrench : (6,) or (n, 6) TCP wrench [F; M] (N, N m), also the load at which the Hertz point contacts are
        linearized; None = zero load (contacts at their ``min_contact_force_N``)
    model : "simplified" (links only) or "detailed" (links + drive + joint contact laws)
    joints : "rigid" or "released"
    state : the inverse kinematics of ``poses`` if already solved (:func:`solve_legs`)
    element_scale : (L, E) or (n, L, E) factors on the compliance of element kind e (order
        ``device.element_names``) in leg i (1 = as modelled, 2 = twice as soft, 0 = rigid): the hook for
        model extensions and for locating an effect by leg and element
    backend : "compiled" (default: the numba kernels of :mod:`femcheck.parallel.chain_kernel`, the same
        equations one pose at a time) or "numpy" (this function's vectorized transcription, the reference)
    joint_rotation_compliance : rad/(N m), every S and U joint's rotations as torsional springs under ``rigid``
        joints (0 = welded; large -> released; :func:`joint_rotation_compliances`); ignored under ``released``
    """
    from femcheck.parallel.compiled import check_backend, evaluate_compiled, evaluate_fused, fused_available
    check_backend(backend)
    if model not in MODELS:
        raise ValueError(f"model: {model!r}; expected one of {list(MODELS)}")
    if joints not in JOINT_IDEALIZATIONS:
        raise ValueError(f"joints: {joints!r}; expected one of {list(JOINT_IDEALIZATIONS)}")
    names = device.element_names
    L = device.n_legs
    c_rot = float(joint_rotation_compliance) if joints == "rigid" else 0.0
    if c_rot and not {"hertz_point", "hertz_line"} <= set(names):
        raise ValueError("joint_rotation_compliance: needs a device whose S and U joints have contact laws "
                         "(element kinds hertz_point and hertz_line)")
    if state is None and backend == "compiled" and fused_available(device, joints):
        # inverse kinematics and chain model in one compiled call; the leg state is solved again only if asked for
        P = as_poses(poses)
        W, scale = _load_and_scale(P.shape[0], L, len(names), wrench, element_scale, device.element_scale)
        out = evaluate_fused(device, P, W, scale, model, joints, c_rot)
        if len(out) == 2:
            _raise_unreachable(device, P, *out)
        K_T, S_T, t, K_leg, W_C, energy, k_h, iterations, contributions = out
        return _result(model, joints, P, lambda: solve_legs(device, P), W, K_T, S_T, t, K_leg, W_C, names, energy,
                       k_h, iterations, contributions)
    state = state if state is not None else solve_legs(device, poses, backend=backend)
    n = state.n
    if not state.ok.all():
        k = int(np.flatnonzero(~state.ok)[0])
        _raise_unreachable(device, state.poses, k, next(i for i, s in enumerate(state.legs) if not s.ok[k]))
    W, scale = _load_and_scale(n, L, len(names), wrench, element_scale, device.element_scale)
    if backend == "compiled":
        out = evaluate_compiled(device, state, W, scale, model, joints, c_rot)
        if out is not None:
            K_T, S_T, t, K_leg, W_C, energy, k_h, iterations = out
            return _result(model, joints, state.poses, state, W, K_T, S_T, t, K_leg, W_C, names, energy, k_h,
                           iterations)
    parts = leg_element_compliances(device, state, model)
    parts = [{name: S * scale[:, i, names.index(name), None, None] for name, S in p.items()} for i, p in enumerate(parts)]
    G = [state.G(i) for i in range(L)]
    N = [np.broadcast_to(np.eye(6), (n, 6, 6)) if joints == "rigid" else released_wrenches(leg, state.legs[i])
         for i, leg in enumerate(device.legs)]
    rot = joint_rotation_compliances(device, state, c_rot) if c_rot else [{} for _ in range(L)]
    S_fixed = [(sum(p.values()) if p else np.zeros((n, 6, 6))) + sum(rot[i].values()) for i, p in enumerate(parts)]
    hertz = {(i, j): v for i, leg in enumerate(device.legs) for j, v in leg.hertz_point.items()} if model == "detailed" else {}
    k_h = {key: hertz_point_contact.hertz_tangent_stiffness(F_min, E, R) * np.ones(n) for key, (E, R, F_min) in hertz.items()}
    ladder = {(i, j): v for i, leg in enumerate(device.legs) for j, v in leg.measured_ladder.items()} if model == "detailed" else {}
    c_lad = {key: ladder_compliance(np.zeros(n), *v) for key, v in ladder.items()}   # start at the ladder's floor

    def ladder_parts(i):
        return [(j, _measured_law_at_C(device.legs[i], state.legs[i], j, c_lad[i, j])
                 * scale[:, i, names.index("measured_law"), None, None]) for (li, j) in c_lad if li == i]

    history = []
    for it in range(_FIXED_POINT_MAX_ITER):
        S_leg = [S_fixed[i] + sum(_translational(scale[:, i, names.index("hertz_point")] / k_h[key])
                                  for key in k_h if key[0] == i)
                 + sum(S for _, S in ladder_parts(i)) for i in range(L)]
        K_leg = [_leg_stiffness(S_leg[i], N[i]) for i in range(L)]
        K_T = sum(np.swapaxes(G[i], -1, -2) @ K_leg[i] @ G[i] for i in range(L))
        K_T = 0.5 * (K_T + np.swapaxes(K_T, -1, -2))
        t = np.linalg.solve(K_T, W[..., None])[..., 0]
        W_C = np.stack([np.einsum("nij,njk,nk->ni", K_leg[i], G[i], t) for i in range(L)], axis=1)
        if not hertz and not ladder:
            break
        change, change_lad = 0.0, 0.0
        for (i, j), v in ladder.items():   # the joint's axial force: along its frame's z axis (the link)
            z = state.legs[i].link_R[:, device.legs[i].measured_law[j][2], :, 2]
            c_new = ladder_compliance(np.abs(np.einsum("ni,ni->n", z, W_C[:, i, :3])), *v)
            change_lad = max(change_lad, float(np.max(np.abs(c_new - c_lad[i, j]) / c_new)))
            c_lad[i, j] = c_new
        for (i, j), (E, R, F_min) in hertz.items():
            k_new = hertz_point_contact.hertz_tangent_stiffness(np.maximum(np.linalg.norm(W_C[:, i, :3], axis=1), F_min), E, R)
            change = max(change, float(np.max(np.abs(k_new - k_h[i, j]) / k_new)))
            k_h[i, j] = k_new
        history.append(max(change, change_lad))
        if change_lad < _LADDER_TOL and change < (_LADDER_TOL if ladder else _FIXED_POINT_TOL):
            break
    else:
        raise ConvergenceError("Hertz linearization fixed point of the parallel device did not converge", history)
    energy = np.zeros((n, L, len(names)))
    for i in range(L):
        for name, S_e in parts[i].items():
            energy[:, i, names.index(name)] += np.einsum("ni,nij,nj->n", W_C[:, i], S_e, W_C[:, i])
        for (li, j) in k_h:
            if li == i:
                energy[:, i, names.index("hertz_point")] += (np.sum(W_C[:, i, :3] ** 2, axis=1)
                                                             * scale[:, i, names.index("hertz_point")] / k_h[li, j])
        for _, S_e in ladder_parts(i):
            energy[:, i, names.index("measured_law")] += np.einsum("ni,nij,nj->n", W_C[:, i], S_e, W_C[:, i])
        for name, S_e in rot[i].items():
            energy[:, i, names.index(name)] += np.einsum("ni,nij,nj->n", W_C[:, i], S_e, W_C[:, i])
    k_h = {**k_h, **{key: 1.0 / c for key, c in c_lad.items()}}
    return _result(model, joints, state.poses, state, W, K_T, np.linalg.inv(K_T), t, np.stack(K_leg, axis=1), W_C,
                   names, energy, k_h, len(history) + 1)


def _load_and_scale(n, L, E, wrench, element_scale, held=None):
    """The wrench (n, 6) and the element compliance factors (n, L, E) broadcast to the poses; ``held`` (L, E): the
    device's own factors (a corrected case's ``[model.element_scale]``), multiplying the given ones."""
    W = np.zeros((n, 6)) if wrench is None else np.array(np.broadcast_to(np.asarray(wrench, float), (n, 6)))
    scale = np.ones((n, L, E)) if element_scale is None else \
        np.array(np.broadcast_to(np.asarray(element_scale, float), (n, L, E)))
    if held is not None:
        scale = scale * held
    return W, scale


def _raise_unreachable(device, poses, k: int, leg: int):
    raise UnreachablePoseError(f"#{k} {np.array2string(poses[k], precision=4)}", leg,
                               f"no inverse-kinematics solution of leg {device.legs[leg].name!r} inside its joint limits")


def _result(model, joints, poses, state, W, K_T, S_T, t, K_leg, W_C, names, energy, k_h, iterations,
            contributions=None) -> ParallelResult:
    if contributions is None:
        work = np.einsum("ni,ni->n", W, t)
        with np.errstate(invalid="ignore", divide="ignore"):
            contributions = np.where(work[:, None] > 0, energy.sum(axis=1) / work[:, None], np.nan)
    return ParallelResult(model=model, joints=joints, poses=poses, wrench=W, K=K_T, S=S_T, twist=t,
                          leg_stiffness=K_leg, leg_wrench=W_C, element_names=names, element_energy=energy,
                          contributions=contributions, hertz_stiffness=k_h, iterations=iterations, state_source=state)


def _translational(c):
    """(n, 6, 6) compliance c I3 on the translations, c (n,)."""
    S = np.zeros(np.shape(c) + (6, 6))
    S[..., 0, 0] = S[..., 1, 1] = S[..., 2, 2] = c
    return S
