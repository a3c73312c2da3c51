"""Compliance-chain stiffness model of the 6-PSU device, vectorized over poses
(seed 000 §4.1, §4.4; docs/conventions.md §4-7, which replaces the paper's garbled eqs. 26, 49-53).

Per chain i the elements ``lg`` (guideway, cantilever of length s_i at B_i), ``act`` (cable + motor,
along the rail), ``sp`` (spherical joint, Hertz point contact at B_i), ``prox`` (proximal link,
cantilever of length L2 at C_i) and ``uj`` (universal joint at C_i) are in series; each element's
local compliance is carried to C_i,

    S_C,e = Jf(C_i - Q_e)^T Rot(R_e) S_e^L Rot(R_e)^T Jf(C_i - Q_e),

and the rigid platform combines the chains at the TCP: ``G_i = Jf(C_i - T)^T``,
``K_T = sum_i G_i^T K_i G_i``, ``t_T = K_T^-1 W_T``, ``W_C,i = K_i G_i t_T``.

Joint idealizations (docs/conventions.md §5): ``rigid`` (the paper: joints carry moments, K_i = S_C,i^-1)
and ``released`` (ideal S/U joints: each chain a two-force member, ``K_T = sum k_i g_i g_i^T``). A finite
``joint_rotation_compliance`` (rad/(N m)) interpolates between them: each passive joint rotation
becomes a torsional spring, i.e. an extra compliance ``c_rot Jp Jp^T`` in the chain (seed 001's
passive-joint elimination with springs instead of free joints).

The detailed model is linear per load case: each spherical joint is linearized at the force its
own chain transmits under the test wrench, found by fixed-point iteration (docs/conventions.md §6).
"""
from __future__ import annotations

import dataclasses
import functools
import logging

import numpy as np

from femcheck.chain.device_parameters import DeviceParameters, device_parameters
# the laws through their modules: the function a module holds when the model runs is the one used
from femcheck.compliance import cantilever_beam, hertz_point_contact
from femcheck.compliance.sections import Section
from femcheck.errors import ConvergenceError
from femcheck.kinematics.frames import guideway_frames, link_frames, rot6, twist_shift
from femcheck.kinematics.psu6 import LegGeometry, as_poses, leg_geometry

log = logging.getLogger(__name__)

ELEMENTS = ("lg", "act", "sp", "prox", "uj")
ELEMENT_NAMES = {"lg": "guideway", "act": "actuation", "sp": "spherical_joint", "prox": "proximal_link",
                 "uj": "universal_joint"}
MODEL_ELEMENTS = {"simplified": ("lg", "prox"), "detailed": ELEMENTS}
JOINT_IDEALIZATIONS = ("rigid", "released")
_LG, _ACT, _SP, _PROX, _UJ = range(5)
_PRESENT = {m: np.broadcast_to(np.array([e in els for e in ELEMENTS], dtype=float), (6, 5)) for m, els in MODEL_ELEMENTS.items()}
_FIXED_POINT_TOL = 1e-12
_FIXED_POINT_MAX_ITER = 200


@dataclasses.dataclass(frozen=True)
class ChainAdjustments:
    """Model extensions applied on top of the case (used by diagnosis and sensitivity studies).

    element_scale: (6, 5) or (n, 6, 5) factors on the compliance of element e (order ``ELEMENTS``) in
    chain i (1 = as modelled, 2 = twice as soft, 0 = rigid). joint_rotation_compliance: compliance
    (rad/(N m)) of every passive joint rotation for ``rigid`` joints (0 = rigid; large -> released).
    """

    element_scale: np.ndarray | None = None
    joint_rotation_compliance: float = 0.0


@dataclasses.dataclass(frozen=True)
class ChainResult:
    """Result of :func:`evaluate` for n poses (SI).

    K, S: (n, 6, 6) TCP stiffness and compliance (twist [d; theta] <- wrench [F; M]);
    twist: (n, 6) TCP deflection under ``wrench`` (n, 6); chain_wrench: (n, 6, 6) wrench each chain
    carries at its C_i; k_sp: (n, 6) Hertz stiffness of each spherical joint (NaN if not modelled);
    element_energy: (n, 6, 5) complementary energy per chain and element (J);
    contributions: (n, 5) share of each element type (sums to 1; NaN at zero load).
    """

    model: str
    joints: str
    poses: np.ndarray
    wrench: np.ndarray
    K: np.ndarray
    S: np.ndarray
    twist: np.ndarray
    chain_wrench: np.ndarray
    k_sp: np.ndarray
    element_energy: np.ndarray
    contributions: np.ndarray
    iterations: int
    legs: LegGeometry = dataclasses.field(repr=False)

    def directional_stiffness(self, direction) -> np.ndarray:
        """(n,) stiffness along a unit translation ``direction`` (3,): 1 / (d^T S_tt d), N/m (seed 000 §4.7)."""
        from femcheck.compliance.directional import directional_stiffness
        return directional_stiffness(self.S, direction)


def _column(x):
    """(n,) parameter arrays -> (n, 1) so they broadcast over the 6 chains; scalars unchanged."""
    return np.asarray(x, dtype=float)[:, None] if np.ndim(x) == 1 else x


def _per_chain(p: DeviceParameters) -> DeviceParameters:
    sec = lambda s: Section(**{f.name: _column(getattr(s, f.name)) if f.name != "shear_factor" else s.shear_factor
                              for f in dataclasses.fields(Section)})
    vals = {f.name: getattr(p, f.name) for f in dataclasses.fields(DeviceParameters)}
    for k, v in vals.items():
        if isinstance(v, Section):
            vals[k] = sec(v)
        elif isinstance(v, np.ndarray):
            vals[k] = _column(v)
    return DeviceParameters(**vals)


def _joint_rotation_twists(legs: LegGeometry) -> tuple[np.ndarray, np.ndarray]:
    """Unit twists at C_i of the passive joint rotations: S joint (n, 6, 6, 3), U joint (n, 6, 6, 2).

    S: [w x (C - B); w] for w = x, y, z. U: [0; a1], [0; a2] with a1 = unit(z_P x u) (fixed in the
    platform) and a2 = u x a1 (fixed in the link); docs/conventions.md §5 "Joint idealization".
    """
    n = legs.n
    W = np.broadcast_to(np.eye(3), (n, 6, 3, 3))  # columns w
    r = legs.C - legs.B
    Jsp = np.concatenate([np.cross(W, r[:, :, None, :]).swapaxes(-1, -2), W], axis=-2)
    zP = legs.R_platform[:, :, 2]
    a1 = np.cross(zP[:, None, :], legs.u)
    a1 /= np.linalg.norm(a1, axis=-1, keepdims=True)
    a2 = np.cross(legs.u, a1)
    zero = np.zeros_like(a1)
    Juj = np.stack([np.concatenate([zero, a1], -1), np.concatenate([zero, a2], -1)], axis=-1)
    return Jsp, Juj


def _element_ingredients(case, legs: LegGeometry, p: DeviceParameters):
    """Guideway tip compliance at B (n,6,6,6, frame U), U-joint translational compliance (n,6,3,3),
    actuation compliance (n,6), link axial compliance (n,6) and link frames (n,6,3,3)."""
    n = legs.n
    R_lg = guideway_frames(case)
    R_B = link_frames(legs.u)
    S_lg_B = rot6(R_lg) @ cantilever_beam.cantilever_compliance(legs.slider, p.E_lg, p.G_lg, p.lg_section, p.beam_shear) @ rot6(R_lg).swapaxes(-1, -2)
    uj_local = np.stack(np.broadcast_arrays(p.c_uc, p.c_uc, p.c_uc + p.c_ub), -1) * np.ones((n, 6, 1))
    S_uj_tt = np.einsum("nlij,nlj,nlkj->nlik", R_B, uj_local, R_B)
    c_act = np.broadcast_to(p.c_act, (n, 6))
    sec = p.prox_section   # the link's axial compliance L / (E A): S22 of the cantilever law
    prox_axial = cantilever_beam.cantilever_terms(p.L2, p.E_prox, p.G_prox, sec.A, sec.Ix, sec.Iy, sec.Jt,
                                                  sec.shear_factor, bool(p.beam_shear))[6] * np.ones((n, 6))
    return S_lg_B, S_uj_tt, c_act, prox_axial, R_B


def _element_compliances_at_C(legs: LegGeometry, p: DeviceParameters, scale, adjust: ChainAdjustments, parts):
    """(n, 6, 5, 6, 6) compliance of each element carried to C_i (frame U), without the Hertz term
    of the spherical joint (its slot holds only the joint-rotation springs, if any)."""
    S_lg_B, S_uj_tt, c_act, _, R_B = parts
    n = legs.n
    S_e = np.zeros((n, 6, 5, 6, 6))
    to_C = twist_shift(legs.C - legs.B)  # Jf(C - B)^T: twist at B -> twist at C
    S_e[:, :, _LG] = to_C @ S_lg_B @ to_C.swapaxes(-1, -2)
    S_e[:, :, _ACT, :3, :3] = c_act[..., None, None] * np.outer(legs.e, legs.e)
    S_e[:, :, _PROX] = rot6(R_B) @ cantilever_beam.cantilever_compliance(p.L2, p.E_prox, p.G_prox, p.prox_section, p.beam_shear) @ rot6(R_B).swapaxes(-1, -2)
    S_e[:, :, _UJ, :3, :3] = S_uj_tt
    S_e = S_e * scale[..., None, None]
    if adjust.joint_rotation_compliance:
        Jsp, Juj = _joint_rotation_twists(legs)
        c_rot = adjust.joint_rotation_compliance
        S_e[:, :, _SP] += c_rot * Jsp @ Jsp.swapaxes(-1, -2)
        S_e[:, :, _UJ] += c_rot * Juj @ Juj.swapaxes(-1, -2)
    return S_e


def _with_case_extension(case, adjust: ChainAdjustments | None) -> ChainAdjustments:
    """``adjust`` on top of what the case itself holds: its ``[model.leg_scale]`` factors multiply the element
    scales, its ``joint_rotation_compliance_rad_per_Nm`` adds to the joint-rotation compliance (a corrected case
    written by ``femcheck diagnose --extended-case``)."""
    adjust = adjust or ChainAdjustments()
    opts = getattr(case, "model", None)
    legs = getattr(opts, "leg_scale", None)
    c_case = float(getattr(opts, "joint_rotation_compliance_rad_per_Nm", 0.0))
    if legs is None:
        return adjust
    f = legs.array()
    if np.all(f == 1.0) and c_case == 0.0:
        return adjust
    scale = f if adjust.element_scale is None else np.asarray(adjust.element_scale, float) * f
    return ChainAdjustments(element_scale=scale, joint_rotation_compliance=adjust.joint_rotation_compliance + c_case)


def chain_element_compliances(case, poses, k_sp=None, *, model: str = "detailed", params=None,
                              adjust: ChainAdjustments | None = None) -> np.ndarray:
    """(n, 6, 5, 6, 6) compliance of element e of chain i carried to C_i, frame U (docs/conventions.md §4).

    ``k_sp`` (n, 6) N/m: the Hertz stiffness to put into the spherical joints (e.g. ``ChainResult.k_sp``);
    None leaves their translational term out. The sum over elements is the chain compliance S_C,i.
    """
    P = as_poses(poses)
    legs = leg_geometry(case, P)
    p = _per_chain(params if params is not None else device_parameters(case))
    adjust = _with_case_extension(case, adjust)
    scale = np.broadcast_to(_PRESENT[model] if adjust.element_scale is None else _PRESENT[model] * adjust.element_scale, (P.shape[0], 6, 5))
    S_e = _element_compliances_at_C(legs, p, scale, adjust, _element_ingredients(case, legs, p))
    if k_sp is not None and _PRESENT[model][0, _SP]:
        S_e[:, :, _SP, :3, :3] += (scale[..., _SP] / np.asarray(k_sp))[..., None, None] * np.eye(3)
    return S_e


def _hertz(F, p: DeviceParameters):
    return hertz_point_contact.hertz_tangent_stiffness(np.maximum(F, p.F_min_sp), p.E_star_sp, p.R_star_sp)


def _check_converged(history, it):
    if it >= _FIXED_POINT_MAX_ITER - 1:
        raise ConvergenceError("Hertz linearization fixed point (docs/conventions.md §6) did not converge", history)


def evaluate(case, poses, wrench=None, *, model: str = "detailed", joints: str | None = None,
             params: DeviceParameters | None = None, adjust: ChainAdjustments | None = None,
             labels=None, backend: str = "compiled", legs: LegGeometry | None = None) -> ChainResult:
    """Stiffness, deflection and element breakdown of the 6-PSU device at n poses.

    Parameters
    ----------
    case : a parallel_device case with the 6-PSU layout (``case.kind == "haptic_6psu"``; its tables
        ``case.geometry``, ``case.guideway``, ... are read from the legs, :mod:`femcheck.case.psu_layout`)
    poses : (n, 6) float, TCP poses [x, y, z, rx, ry, rz] (m, rad; rotation vector)
    wrench : (6,) or (n, 6) float, TCP wrench [Fx, Fy, Fz, Mx, My, Mz] (N, N m); also the load at which
        the Hertz contacts are linearized. None = zero load (joints at ``min_contact_force_N``).
    model : "simplified" (lg + prox) or "detailed" (all five elements)
    joints : "rigid" | "released" | None (the case's ``[model] joint_rotations``)
    params : element parameters (default: from the case; arrays of shape (n,) for sweeps)
    adjust : :class:`ChainAdjustments` (element scales, joint rotation compliance)
    labels : optional pose names for error messages (e.g. "P3")
    legs : the inverse kinematics of ``poses`` if already computed (``leg_geometry(case, poses)``), so
        that sweeps over several load cases do not repeat it
    backend : "compiled" (numba kernel, default) or "numpy" (the readable vectorized reference);
        the two agree to 1e-10 relative (tests/test_chain_backends.py)
    """
    if model not in MODEL_ELEMENTS:
        raise ValueError(f"model: {model!r}; expected one of {list(MODEL_ELEMENTS)}")
    joints = joints or case.model.joint_rotations
    if joints not in JOINT_IDEALIZATIONS:
        raise ValueError(f"joints: {joints!r}; expected one of {list(JOINT_IDEALIZATIONS)}")
    P = as_poses(poses)
    n = P.shape[0]
    W = np.zeros((n, 6)) if wrench is None else np.array(np.broadcast_to(np.asarray(wrench, float), (n, 6)))
    if legs is None:
        legs = leg_geometry(case, P, labels=labels)
    elif legs.n != n:
        raise ValueError(f"legs: computed for {legs.n} poses, got {n} poses")
    adjust = _with_case_extension(case, adjust)
    present = _PRESENT[model]
    scale = present if adjust.element_scale is None else present * np.asarray(adjust.element_scale, float)
    scale = np.broadcast_to(scale, (n, 6, 5))

    if backend == "compiled":
        return _evaluate_compiled(case, model, joints, P, W, legs, params, adjust, scale)
    if backend != "numpy":
        raise ValueError(f"backend: {backend!r}; expected 'compiled' or 'numpy'")
    p = _per_chain(params if params is not None else device_parameters(case))
    e = legs.e
    S_lg_B, S_uj_tt, c_act, prox_axial, R_B = _element_ingredients(case, legs, p)
    sp_present = bool(present[0, _SP] > 0)

    if joints == "released":
        u = legs.u
        a = np.empty((n, 6, 5))
        a[..., _LG] = np.einsum("nli,nlij,nlj->nl", u, S_lg_B[..., :3, :3], u)
        a[..., _ACT] = c_act * (u @ e) ** 2
        a[..., _SP] = 0.0
        a[..., _PROX] = prox_axial
        a[..., _UJ] = np.einsum("nli,nlij,nlj->nl", u, S_uj_tt, u)
        a = a * scale
        a_fixed = a.sum(-1)
        g = np.concatenate([u, np.cross(legs.C - legs.tcp[:, None, :], u)], axis=-1)
        c_sp = np.zeros((n, 6))
        k_sp = np.full((n, 6), np.nan)
        history = []
        for it in range(_FIXED_POINT_MAX_ITER):
            k = 1.0 / (a_fixed + c_sp)
            K_T = np.einsum("nl,nla,nlb->nab", k, g, g)
            t = np.linalg.solve(K_T, W[..., None])[..., 0]
            f = k * np.einsum("nla,na->nl", g, t)
            if not sp_present:
                break
            k_new = _hertz(np.abs(f), p)
            change = 0.0 if it == 0 else float(np.max(np.abs(k_new - k_sp) / k_new))
            history.append(change)
            k_sp = k_new
            c_sp = scale[..., _SP] / k_sp
            if it > 0 and change < _FIXED_POINT_TOL:
                k = 1.0 / (a_fixed + c_sp)
                K_T = np.einsum("nl,nla,nlb->nab", k, g, g)
                t = np.linalg.solve(K_T, W[..., None])[..., 0]
                f = k * np.einsum("nla,na->nl", g, t)
                break
            _check_converged(history, it)
        a[..., _SP] = c_sp
        chain_wrench = np.concatenate([f[..., None] * u, np.zeros((n, 6, 3))], axis=-1)
        energy = (f**2)[..., None] * a
        iterations = it + 1
    else:
        G = twist_shift(legs.C - legs.tcp[:, None, :])
        S_e = _element_compliances_at_C(legs, p, scale, adjust, (S_lg_B, S_uj_tt, c_act, prox_axial, R_B))
        S_fixed = S_e.sum(axis=2)
        M = np.linalg.inv(S_fixed)
        M = 0.5 * (M + M.swapaxes(-1, -2))
        Gt = G.swapaxes(-1, -2)
        K0 = np.einsum("nlai,nlij,nljb->nab", Gt, M, G)
        k_sp = np.full((n, 6), np.nan)
        if sp_present:
            # Woodbury with the eigenbasis of M's force block: (S_fixed + c I3)^-1 = M - N diag(c/(1+c lam)) N^T,
            # so each fixed-point iteration only re-weights 18 rank-one terms instead of inverting 6x6 matrices.
            lam, Q = np.linalg.eigh(M[..., :3, :3])
            N = M[..., :, :3] @ Q
            H = Gt @ N
            MG_force = (M @ G)[..., :3, :]
            N_force = N[..., :3, :]
            w = np.zeros((n, 6, 3))
            history = []
            for it in range(_FIXED_POINT_MAX_ITER):
                K_T = K0 - np.einsum("nlaj,nlj,nlbj->nab", H, w, H)
                t = np.linalg.solve(K_T, W[..., None])[..., 0]
                F = np.einsum("nlij,nj->nli", MG_force, t) - np.einsum("nlij,nlj->nli", N_force, w * np.einsum("nlaj,na->nlj", H, t))
                k_new = _hertz(np.linalg.norm(F, axis=-1), p)
                change = 0.0 if it == 0 else float(np.max(np.abs(k_new - k_sp) / k_new))
                history.append(change)
                k_sp = k_new
                c_sp = (scale[..., _SP] / k_sp)[..., None]
                w = c_sp / (1.0 + c_sp * lam)
                if it > 0 and change < _FIXED_POINT_TOL:
                    break
                _check_converged(history, it)
            iterations = it + 1
            K_chain = M - np.einsum("nlaj,nlj,nlbj->nlab", N, w, N)
            S_e[:, :, _SP, :3, :3] += c_sp[..., None] * np.eye(3)
        else:
            K_chain = M
            iterations = 1
        K_T = np.einsum("nlai,nlij,nljb->nab", Gt, K_chain, G)
        t = np.linalg.solve(K_T, W[..., None])[..., 0]
        chain_wrench = np.einsum("nlij,nljk,nk->nli", K_chain, G, t)
        energy = np.einsum("nli,nleij,nlj->nle", chain_wrench, S_e, chain_wrench)

    K_T = 0.5 * (K_T + K_T.swapaxes(-1, -2))
    S_T = np.linalg.inv(K_T)
    work = np.einsum("ni,ni->n", W, t)
    with np.errstate(invalid="ignore", divide="ignore"):
        contributions = np.where(work[:, None] > 0, energy.sum(axis=1) / work[:, None], np.nan)
    return ChainResult(model=model, joints=joints, poses=P, wrench=W, K=K_T, S=S_T, twist=t,
                       chain_wrench=chain_wrench, k_sp=k_sp, element_energy=energy,
                       contributions=contributions, iterations=iterations, legs=legs)


def pack_parameters(p: DeviceParameters, n: int) -> np.ndarray:
    """(n, N_PARAMS) per-pose parameter table for the compiled kernel (column order in the kernel module)."""
    from femcheck.chain import haptic_6psu_kernel as kern
    lg, pr = p.lg_section, p.prox_section
    cols = [p.E_lg, p.G_lg, lg.A, lg.Ix, lg.Iy, lg.Jt, lg.shear_factor, p.E_prox, p.G_prox, pr.A, pr.Ix, pr.Iy,
            pr.Jt, pr.shear_factor, p.L2, p.c_act, p.E_star_sp, p.R_star_sp, p.F_min_sp, p.c_uc, p.c_ub]
    assert len(cols) == kern.N_PARAMS
    out = np.empty((n, kern.N_PARAMS))
    for j, c in enumerate(cols):
        out[:, j] = np.reshape(c, -1) if np.ndim(c) else c
    return out


def _case_constants(case):
    """Per-case constants of the compiled path, cached per case and law functions (cases are immutable; a law
    replaced in its module gives new constants)."""
    from femcheck.compliance.kernel_laws import law_functions
    return _case_constants_for(case, law_functions())


@functools.lru_cache(maxsize=32)
def _case_constants_for(case, laws):
    p = device_parameters(case)
    return p, pack_parameters(p, 1), guideway_frames(case)


def _evaluate_compiled(case, model, joints, P, W, legs, params, adjust, scale) -> ChainResult:
    from femcheck.chain import haptic_6psu_kernel as kern
    n = P.shape[0]
    p, packed1, R_lg = _case_constants(case)
    if params is None:
        packed = np.broadcast_to(packed1, (n, packed1.shape[1]))
    else:
        p, packed = params, pack_parameters(params, n)
    K = np.empty((n, 6, 6))
    t = np.empty((n, 6))
    Wc = np.empty((n, 6, 6))
    ksp = np.full((n, 6), np.nan)
    energy = np.empty((n, 6, 5))
    iters = np.zeros(n, dtype=np.int64)
    sp_present = bool(scale[..., _SP].any())
    from femcheck.compliance.kernel_laws import kernel_laws
    status = kern.chain_kernel(*kernel_laws(), legs.B, legs.C, legs.u, legs.tcp, np.ascontiguousarray(legs.R_platform[:, :, 2]),
                               legs.slider, R_lg, legs.e, packed,
                               np.ascontiguousarray(scale), W, joints == "released", sp_present, bool(p.beam_shear),
                               float(adjust.joint_rotation_compliance), K, t, Wc, ksp, energy, iters)
    if status < 0:
        raise np.linalg.LinAlgError(f"chain or platform stiffness not positive definite at pose #{-status - 1}")
    if status:
        raise ConvergenceError(f"Hertz linearization fixed point (docs/conventions.md §6) did not converge at pose #{status - 1}",
                               [], {"pose": int(status - 1)})
    S_T = np.linalg.inv(K)
    work = np.einsum("ni,ni->n", W, t)
    with np.errstate(invalid="ignore", divide="ignore"):
        contributions = np.where(work[:, None] > 0, energy.sum(axis=1) / work[:, None], np.nan)
    if not sp_present:
        ksp[:] = np.nan
    return ChainResult(model=model, joints=joints, poses=P, wrench=W, K=K, S=S_T, twist=t, chain_wrench=Wc,
                       k_sp=ksp, element_energy=energy, contributions=contributions,
                       iterations=int(iters.max(initial=0)), legs=legs)
