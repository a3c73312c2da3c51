"""The 6-PSU's compliance chain in the paper's five elements, computed by the general parallel-device model
(seed 000 §4.1, §4.4; docs/conventions.md §4-7, which replaces the paper's garbled eqs. 26, 49-53).

Per chain i the elements ``lg`` (guideway, cantilever of length s_i at B_i), ``act`` (cable + motor, along the
rail), ``sp`` (spherical joint, Hertz point contact at B_i), ``prox`` (proximal link, cantilever of length L2 at
C_i) and ``uj`` (universal joint at C_i) are in series; the rigid platform combines the chains at the TCP. The
equations, the inverse kinematics and the Hertz fixed point are those of :mod:`femcheck.parallel.chain_model`
(compiled: :mod:`femcheck.parallel.chain_kernel`) on the case's legs: this module only names the 6-PSU's element
kinds in the paper's order and writes the chain-model parameters (:func:`femcheck.chain.device_parameters`, with
the case's ``[model.law_scale]`` and any overrides of a sweep) into the legs.

Element kinds of the legs and the paper's elements: ``guideway`` = lg, ``drive`` = act, ``hertz_point`` = sp,
``proximal_link`` = prox, ``hertz_line`` = uj.

Joint idealizations (docs/conventions.md §5): ``rigid`` (the paper: joints carry moments) and ``released`` (ideal
S/U joints: each chain a two-force member). A finite ``joint_rotation_compliance`` (rad/(N m)) interpolates
between them: each passive joint rotation becomes a torsional spring
(:func:`femcheck.parallel.chain_model.joint_rotation_compliances`; its energy counts to the sp and uj elements).
"""
from __future__ import annotations

import dataclasses
import functools

import numpy as np

from femcheck.chain.device_parameters import DeviceParameters, device_parameters
from femcheck.compliance.sections import Section
from femcheck.errors import UnreachablePoseError
from femcheck.parallel import chain_model
from femcheck.parallel.leg_kinematics import as_poses, solve_legs

ELEMENTS = ("lg", "act", "sp", "prox", "uj")
ELEMENT_NAMES = {"lg": "guideway", "act": "actuation", "sp": "spherical_joint", "prox": "proximal_link",
                 "uj": "universal_joint"}
#: the element kind of the legs (``ParallelDevice.element_names``) that is each of the paper's elements
ELEMENT_KINDS = {"lg": "guideway", "act": "drive", "sp": "hertz_point", "prox": "proximal_link", "uj": "hertz_line"}
_INDEX = {kind: k for k, kind in enumerate(ELEMENT_KINDS[e] for e in ELEMENTS)}
MODEL_ELEMENTS = {"simplified": ("lg", "prox"), "detailed": ELEMENTS}
JOINT_IDEALIZATIONS = ("rigid", "released")
_SP, _UJ = ELEMENTS.index("sp"), ELEMENTS.index("uj")
_PRESENT = {m: np.array([e in els for e in ELEMENTS], dtype=float) for m, els in MODEL_ELEMENTS.items()}


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
class ChainResult(chain_model.TcpResult):
    """Result of :func:`evaluate` for n poses (SI): :class:`~femcheck.parallel.chain_model.TcpResult` (K, S, twist
    under ``wrench``) and chain_wrench: (n, 6, 6) wrench each chain carries at its C_i; k_sp: (n, 6) Hertz
    stiffness of each spherical joint (NaN if not modelled); element_energy: (n, 6, 5) complementary energy per
    chain and element (J); contributions: (n, 5) share of each element type (sums to 1; NaN at zero load).
    """

    chain_wrench: np.ndarray
    k_sp: np.ndarray
    element_energy: np.ndarray
    contributions: np.ndarray
    iterations: int
    #: the 6-PSU leg geometry of ``poses`` (a LegGeometry), or a function computing it on first use of :attr:`legs`
    legs_source: object = dataclasses.field(repr=False, compare=False)

    @functools.cached_property
    def legs(self):
        """The leg geometry of ``poses`` (:func:`femcheck.kinematics.psu6.leg_geometry`)."""
        src = self.legs_source
        return src() if callable(src) else src


def psu_device(case, params: DeviceParameters | None = None):
    """The case's legs (``case.device``) with the chain-model parameters ``params`` (scalars; default
    ``device_parameters(case)``) written into them: the guideway and proximal-link sections and moduli, the drive
    compliance, the spherical joints' Hertz constants and the universal joints' line-contact compliances."""
    if params is None:
        from femcheck.compliance.kernel_laws import law_functions
        return _default_device(case, law_functions())
    p = params
    links = {"guideway": (p.E_lg, p.G_lg, p.lg_section), "proximal_link": (p.E_prox, p.G_prox, p.prox_section)}
    legs = []
    for leg in case.device.legs:
        new_links = tuple(dataclasses.replace(ln, E=float(links[ln.name][0]), G=float(links[ln.name][1]),
                                              section=links[ln.name][2]) if ln.name in links else ln for ln in leg.links)
        hp = {k: (float(p.E_star_sp), float(p.R_star_sp), float(p.F_min_sp)) for k in leg.hertz_point}
        hl = {k: (float(p.c_uc), float(p.c_ub), m) for k, (_, _, m) in leg.hertz_line.items()}
        legs.append(dataclasses.replace(leg, links=new_links, hertz_point=hp, hertz_line=hl,
                                        drive_compliance=float(p.c_act)))
    return dataclasses.replace(case.device, legs=tuple(legs), beam_shear=bool(p.beam_shear))


@functools.lru_cache(maxsize=32)
def _default_device(case, laws):
    """:func:`psu_device` of the case's own parameters, once per case and law functions (cases are immutable; a law
    replaced in its module gives a new device)."""
    return psu_device(case, device_parameters(case))


def _parameter_groups(params: DeviceParameters, n: int):
    """[(pose indices, scalar DeviceParameters)]: the poses sharing one set of values of the (n,) arrays."""
    fields = [f.name for f in dataclasses.fields(DeviceParameters)]
    cols, where = [], []
    for name in fields:
        v = getattr(params, name)
        if isinstance(v, Section):
            for g in dataclasses.fields(Section):
                cols.append(np.broadcast_to(np.asarray(getattr(v, g.name), float).reshape(-1), (n,)))
                where.append((name, g.name))
        elif name != "beam_shear":
            cols.append(np.broadcast_to(np.asarray(v, float).reshape(-1), (n,)))
            where.append((name, None))
    table = np.stack(cols, axis=1)
    rows, inverse = np.unique(table, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    out = []
    for g, row in enumerate(rows):
        vals = {"beam_shear": params.beam_shear}
        secs: dict = {}
        for (name, sub), x in zip(where, row):
            if sub is None:
                vals[name] = float(x)
            else:
                secs.setdefault(name, {})[sub] = float(x)
        for name, kw in secs.items():
            vals[name] = Section(**kw)
        out.append((np.flatnonzero(inverse == g), DeviceParameters(**vals)))
    return out


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


def _columns(device) -> list[int]:
    """The columns of ``device.element_names`` in the order of :data:`ELEMENTS`."""
    names = device.element_names
    return [names.index(ELEMENT_KINDS[e]) for e in ELEMENTS]


def _general_scale(device, scale: np.ndarray) -> np.ndarray:
    """(n, 6, 5) factors in the order of :data:`ELEMENTS` -> (n, 6, E) in the order of ``device.element_names``."""
    out = np.ones(scale.shape[:2] + (len(device.element_names),))
    out[:, :, _columns(device)] = scale
    return out


def _scale(model, adjust, n) -> np.ndarray:
    present = _PRESENT[model]
    s = present if adjust.element_scale is None else present * np.asarray(adjust.element_scale, float)
    return np.broadcast_to(s, (n, 6, 5))


def _sphere_joints(device) -> list[tuple[int, int]]:
    """(leg, joint index) of each leg's spherical joint."""
    return [(l, leg.joint_types.index("S")) for l, leg in enumerate(device.legs)]


def chain_element_compliances(case, poses, k_sp=None, *, model: str = "detailed", params=None,
                              adjust: ChainAdjustments | None = None) -> np.ndarray:
    """(n, 6, 5, 6, 6) compliance of element e of chain i carried to C_i, frame U (docs/conventions.md §4).

    ``k_sp`` (n, 6) N/m: the Hertz stiffness to put into the spherical joints (e.g. ``ChainResult.k_sp``);
    None leaves their translational term out. The sum over elements is the chain compliance S_C,i.
    Element by element as :func:`femcheck.parallel.chain_model.leg_element_compliances` and
    :func:`~femcheck.parallel.chain_model.joint_rotation_compliances` give them.
    """
    P = as_poses(poses)
    n = P.shape[0]
    adjust = _with_case_extension(case, adjust)
    scale = _scale(model, adjust, n)
    groups = [(np.arange(n), None)] if params is None else _parameter_groups(params, n)
    S_e = np.zeros((n, 6, 5, 6, 6))
    for idx, p in groups:
        dev = psu_device(case, p)
        state = solve_legs(dev, P[idx])
        parts = chain_model.leg_element_compliances(dev, state, model)
        c_rot = float(adjust.joint_rotation_compliance)
        rot = chain_model.joint_rotation_compliances(dev, state, c_rot) if c_rot else [{}] * 6
        for l in range(6):
            for name, S in parts[l].items():
                e = _INDEX[name]
                S_e[idx, l, e] += S * scale[idx, l, e, None, None]
            for name, S in rot[l].items():
                S_e[idx, l, _INDEX[name]] += S
    if k_sp is not None and _PRESENT[model][_SP]:
        S_e[:, :, _SP, :3, :3] += (scale[..., _SP] / np.asarray(k_sp))[..., None, None] * np.eye(3)
    return S_e


def evaluate(case, poses, wrench=None, *, model: str = "detailed", joints: str | None = None,
             params: DeviceParameters | None = None, adjust: ChainAdjustments | None = None,
             labels=None, backend: str = "compiled", legs=None) -> ChainResult:
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
    params : element parameters (default: from the case; arrays of shape (n,) for sweeps: the poses sharing one
        set of values are evaluated together)
    adjust : :class:`ChainAdjustments` (element scales, joint rotation compliance)
    labels : optional pose names for error messages (e.g. "P3")
    legs : the 6-PSU leg geometry of ``poses`` if already computed (``leg_geometry(case, poses)``), kept as the
        result's ``legs`` (the model solves its legs in the compiled call)
    backend : "compiled" (numba kernel, default) or "numpy" (the readable vectorized reference of
        :func:`femcheck.parallel.chain_model.evaluate`)
    """
    if model not in MODEL_ELEMENTS:
        raise ValueError(f"model: {model!r}; expected one of {list(MODEL_ELEMENTS)}")
    joints = joints or case.model.joint_rotations
    if joints not in JOINT_IDEALIZATIONS:
        raise ValueError(f"joints: {joints!r}; expected one of {list(JOINT_IDEALIZATIONS)}")
    P = as_poses(poses)
    n = P.shape[0]
    W = np.zeros((n, 6)) if wrench is None else np.array(np.broadcast_to(np.asarray(wrench, float), (n, 6)))
    if legs is not None and legs.n != n:
        raise ValueError(f"legs: computed for {legs.n} poses, got {n} poses")
    adjust = _with_case_extension(case, adjust)
    scale = _scale(model, adjust, n)
    groups = [(None, psu_device(case))] if params is None else \
        [(idx, psu_device(case, p)) for idx, p in _parameter_groups(params, n)]
    parts = []
    for idx, dev in groups:
        sel = slice(None) if idx is None else idx
        try:
            r = chain_model.evaluate(dev, P[sel], W[sel], model=model, joints=joints,
                                     element_scale=_general_scale(dev, scale[sel]), backend=backend,
                                     joint_rotation_compliance=adjust.joint_rotation_compliance)
        except UnreachablePoseError:
            from femcheck.kinematics.psu6 import leg_geometry
            leg_geometry(case, P, labels=labels)   # names the pose by its label where the 6-PSU IK fails too
            raise
        cols = _columns(dev)
        k_sp = np.stack([r.hertz_stiffness.get(key, np.full(r.poses.shape[0], np.nan)) for key in _sphere_joints(dev)],
                        axis=1)
        parts.append((sel, r.K, r.S, r.twist, r.leg_wrench, k_sp, r.element_energy[:, :, cols], r.contributions[:, cols],
                      r.iterations))
    if len(parts) == 1:
        _, K, S, t, Wc, k_sp, energy, contributions, iterations = parts[0]
    else:
        shapes = ((6, 6), (6, 6), (6,), (6, 6), (6,), (6, 5), (5,))
        K, S, t, Wc, k_sp, energy, contributions = (np.empty((n,) + s) for s in shapes)
        for sel, *arrays, _ in parts:
            for out, a in zip((K, S, t, Wc, k_sp, energy, contributions), arrays):
                out[sel] = a
        iterations = max(p[-1] for p in parts)
    if model == "simplified":
        k_sp = np.full((n, 6), np.nan)
    src = legs if legs is not None else functools.partial(_leg_geometry, case, P)
    return ChainResult(model=model, joints=joints, poses=P, wrench=W, K=K, S=S, twist=t, chain_wrench=Wc, k_sp=k_sp,
                       element_energy=energy, contributions=contributions, iterations=int(iterations), legs_source=src)


def _leg_geometry(case, P):
    from femcheck.kinematics.psu6 import leg_geometry
    return leg_geometry(case, P)
