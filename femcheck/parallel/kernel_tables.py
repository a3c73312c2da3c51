"""A :class:`~femcheck.parallel.device.ParallelDevice` compiled into flat arrays for the numba kernels of
:mod:`femcheck.parallel.chain_kernel`.

Every leg is padded to the largest leg of the device: ``nd`` freedoms, ``nc`` joint centres, ``nl`` links, and
its joint laws. The element kinds index ``device.element_names`` (the columns of ``element_energy``);
-1 marks an element kind the leg does not have. Nothing here is physics: it is the same description as the
:class:`~femcheck.parallel.device.Leg` objects, laid out for machine code.

Closed-form inverse kinematics (``ik_kind``): 1 for an ``F-P*-S-U`` leg (the 6-PSU's: slider position from the
sphere ``|C - B| = L``), 2 for a ``U-P*-S`` strut (leg length ``|p + R b - a|``), 3 for an ``R*-U-U`` leg (the
Delta's: crank angle from the circle of the elbow meeting the sphere of the rod); 0 = numeric only. A closed form
needs the S joint's three axes orthonormal and right-handed and each U joint's two axes not parallel.
"""
from __future__ import annotations

import dataclasses
import weakref

import numpy as np

#: ik_kind codes
IK_NUMERIC, IK_PSU, IK_UPS, IK_RUU = 0, 1, 2, 3


@dataclasses.dataclass(frozen=True)
class DeviceTables:
    """Flat arrays of one device (shapes with L legs; see the kernel module for their use).

    ``tab``: the tuple handed to the kernels; ``released_ok``: every leg's passive twists are independent at
    the home pose (the kernels' Householder null space needs it; otherwise released joints use numpy);
    ``hp_joint`` (L, nhp): joint index of each Hertz point contact (-1 padding); ``ml_joint`` (L, nml): of each
    measured joint law (its axial tangent, for a force ladder, follows the Hertz stiffnesses in the kernel's output).
    """

    tab: tuple
    n_elem: int
    released_ok: bool
    hp_joint: np.ndarray
    ik_kind: np.ndarray
    #: (L, nml) joint index of each measured law (-1 padding)
    ml_joint: np.ndarray | None = None


_CACHE: dict[int, DeviceTables] = {}


def device_tables(device) -> DeviceTables:
    """The :class:`DeviceTables` of ``device``, built once per device object (devices are immutable)."""
    key = id(device)
    hit = _CACHE.get(key)
    if hit is None:
        hit = _build(device)
        _CACHE[key] = hit
        weakref.finalize(device, _CACHE.pop, key, None)
    return hit


def _orthonormal_right(A) -> bool:
    return bool(np.allclose(A.T @ A, np.eye(3), atol=1e-12) and np.linalg.det(A) > 0)


def _ik_kind(leg) -> int:
    kinds = "".join(leg.dof_kind)
    if leg.joint_types == ("R", "U", "U") and kinds == "RRRRR" and leg.actuated_dof == 0:
        parallel = [np.linalg.norm(np.cross(*leg.dof_axis[k:k + 2])) < 1e-6 for k in (1, 3)]
        return IK_NUMERIC if any(parallel) else IK_RUU
    if leg.joint_types == ("F", "P", "S", "U") and kinds == "PRRRRR" and leg.actuated_dof == 0:
        s_axes, u_axes = leg.dof_axis[1:4], leg.dof_axis[4:6]
    elif leg.joint_types == ("U", "P", "S") and kinds == "RRPRRR" and leg.actuated_dof == 2:
        s_axes, u_axes = leg.dof_axis[3:6], leg.dof_axis[0:2]
    else:
        return IK_NUMERIC
    if not _orthonormal_right(s_axes.T) or np.linalg.norm(np.cross(*u_axes)) < 1e-6:
        return IK_NUMERIC
    return IK_PSU if leg.joint_types[0] == "F" else IK_UPS


def _ruu_home_branch(leg) -> float:
    """Sign sigma of the crank root ``q0 = atan2(beta, alpha) - sigma acos(kappa / rho)`` of an R*-U-U leg that is
    the home configuration (q0 = 0; the R*-U-U closed form of chain_kernel._ik_range): at home ``kappa = alpha``, so
    ``acos(kappa / rho) = |atan2(beta, alpha)|`` and sigma is the sign of ``beta = 2 d . (a x v_perp)``."""
    a, A = leg.dof_axis[0], leg.dof_point[0]
    v = leg.centres[1] - A
    v_perp = v - (v @ a) * a
    d = leg.centres[2] - A - (v @ a) * a
    return float(np.sign(d @ np.cross(a, v_perp)) or 1.0)


def _build(device) -> DeviceTables:
    legs = device.legs
    L = len(legs)
    names = device.element_names
    nd = max(leg.n_dof for leg in legs)
    nc = max(len(leg.centres) for leg in legs)
    nl = max(max(len(leg.links) for leg in legs), 1)
    nhl = max(max(len(leg.hertz_line) for leg in legs), 1)
    nhp = max(max(len(leg.hertz_point) for leg in legs), 1)
    nlim = max(max(len(leg.limits) for leg in legs), 1)
    # n_dof, n_centres, n_links, n_hl, n_hp, n_lim, actuated, ik_kind, a limit on a passive freedom
    i_n = np.zeros((L, 9), np.int64)
    dkind = np.zeros((L, nd), np.int64)  # 0 R, 1 P
    daxis = np.zeros((L, nd, 3))
    dpoint = np.zeros((L, nd, 3))
    passive = np.zeros((L, nd), np.int64)
    cen = np.zeros((L, nc, 3))
    cen_first = np.zeros((L, nc), np.int64)
    lk_i = np.full((L, nl, 4), -1, np.int64)    # start, end, body (freedoms moving the link), element kind
    lk_x = np.zeros((L, nl, 3))
    lk_p = np.ones((L, nl, 7))                  # E, G, A, Ix, Iy, Jt, kappa
    hl_c = np.zeros((L, nhl, 2))
    hl_link = np.zeros((L, nhl), np.int64)
    hp = np.ones((L, nhp, 3))                   # E*, R*, F_min
    hp_joint = np.full((L, nhp), -1, np.int64)
    lim_d = np.zeros((L, nlim), np.int64)
    lim = np.zeros((L, nlim, 2))
    f_leg = np.zeros((L, 2))                    # drive compliance, home branch of the F-P-S-U / R-U-U root
    b_plat = np.zeros((L, 3))
    kinds = np.array([names.index("drive"),
                      names.index("hertz_point") if "hertz_point" in names else -1,
                      names.index("hertz_line") if "hertz_line" in names else -1], np.int64)
    released_ok = True
    ik = np.zeros(L, np.int64)
    for l, leg in enumerate(legs):
        ik[l] = _ik_kind(leg)
        i_n[l] = [leg.n_dof, len(leg.centres), len(leg.links), len(leg.hertz_line), len(leg.hertz_point),
                  len(leg.limits), leg.actuated_dof, ik[l], any(d != leg.actuated_dof for d, _, _ in leg.limits)]
        for k in range(leg.n_dof):
            dkind[l, k] = 0 if leg.dof_kind[k] == "R" else 1
            passive[l, k] = int(k != leg.actuated_dof)
        daxis[l, :leg.n_dof] = leg.dof_axis
        dpoint[l, :leg.n_dof] = leg.dof_point
        cen[l, :len(leg.centres)] = leg.centres
        for m in range(len(leg.centres)):
            cen_first[l, m] = leg.dofs_before(int(np.flatnonzero(leg.joint_centre == m)[0]))
        for m, ln in enumerate(leg.links):
            body = leg.dofs_through(int(np.flatnonzero(leg.joint_centre == ln.start)[0]))
            lk_i[l, m] = [ln.start, ln.end, body, -1 if ln.section is None else names.index(ln.name)]
            lk_x[l, m] = ln.x_axis
            if ln.section is not None:
                s = ln.section
                lk_p[l, m] = [ln.E, ln.G, s.A, s.Ix, s.Iy, s.Jt, s.shear_factor]
        for j, (c_uc, c_ub, m) in enumerate(leg.hertz_line.values()):
            hl_c[l, j] = c_uc, c_ub
            hl_link[l, j] = m
        for j, (k, v) in enumerate(leg.hertz_point.items()):
            hp[l, j] = v
            hp_joint[l, j] = k
        for j, (d, lo, hi) in enumerate(leg.limits):
            lim_d[l, j] = d
            lim[l, j] = lo, hi
        f_leg[l, 0] = leg.drive_compliance
        if ik[l] == IK_PSU:
            f_leg[l, 1] = np.sign(leg.dof_axis[0] @ (leg.centres[2] - leg.centres[1])) or 1.0
        elif ik[l] == IK_RUU:
            f_leg[l, 1] = _ruu_home_branch(leg)
        b_plat[l] = leg.b_platform
        # the kernels' null space of the passive twists needs them independent (checked at the home configuration)
        tw = _home_twists(leg)[leg.passive_dofs]
        if tw.size and np.linalg.matrix_rank(tw, tol=1e-9 * np.abs(tw).max()) < len(tw):
            released_ok = False
    R_home = np.ascontiguousarray(_rotvec_matrix(device.home_pose[3:]))
    ml_i, ml_S, ml_n, ml_F, ml_d, ml_joint = _measured_law_tables(device)
    tab = (i_n, dkind, daxis, dpoint, passive, cen, cen_first, lk_i, lk_x, lk_p, hl_c, hl_link, hp, lim_d, lim,
           f_leg, b_plat, kinds, R_home, np.asarray(device.tcp_offset, float).copy(), _joint_rotation_table(device),
           (ml_i, ml_S, ml_n, ml_F, ml_d))   # measured laws: keep them last (tab[-1])
    return DeviceTables(tab=tab, n_elem=len(names), released_ok=released_ok, hp_joint=hp_joint, ik_kind=ik,
                        ml_joint=ml_joint)


def _measured_law_tables(device):
    """FE-measured joint laws: ml_i (L, nml, 3) centre, link, element kind (-1 padding); ml_S (L, nml, 6, 6) the
    compliance at the joint centre in the link frame (``Leg.measured_law``); ml_n (L, nml) force-ladder length (0: a
    constant law), ml_F, ml_d (L, nml, k) its forces and approaches (``Leg.measured_ladder``); ml_joint (L, nml)."""
    legs = device.legs
    nml = max(max(len(leg.measured_law) for leg in legs), 1)
    nk = max([len(F) for leg in legs for F, _ in leg.measured_ladder.values()] + [1])
    ml_i = np.full((len(legs), nml, 3), -1, np.int64)
    ml_S = np.zeros((len(legs), nml, 6, 6))
    ml_n = np.zeros((len(legs), nml), np.int64)
    ml_F = np.ones((len(legs), nml, nk))
    ml_d = np.ones((len(legs), nml, nk))
    ml_joint = np.full((len(legs), nml), -1, np.int64)
    if any(leg.measured_law for leg in legs):
        kind = device.element_names.index("measured_law")
        for l, leg in enumerate(legs):
            for j, (k, (S, c, m)) in enumerate(leg.measured_law.items()):
                ml_i[l, j] = c, m, kind
                ml_S[l, j] = S
                ml_joint[l, j] = k
                if k in leg.measured_ladder:
                    F, d = leg.measured_ladder[k]
                    ml_n[l, j] = len(F)
                    ml_F[l, j, :len(F)] = F
                    ml_d[l, j, :len(F)] = d
    return ml_i, ml_S, ml_n, ml_F, ml_d, ml_joint


def _joint_rotation_table(device) -> np.ndarray:
    """(L, nj, 3) int: the S and U joints of every leg whose rotations take a joint-rotation compliance
    (:func:`femcheck.parallel.chain_model.joint_rotation_compliances`): centre index, the link ending at the joint
    (U: its two rotations are those normal to that link), kind (0 S, 1 U); -1 padding."""
    rows = [[(int(leg.joint_centre[k]), int(leg.joint_centre[k]) - 1, 0 if t == "S" else 1)
             for k, t in enumerate(leg.joint_types) if t in ("S", "U")] for leg in device.legs]
    out = np.full((len(rows), max(max(len(r) for r in rows), 1), 3), -1, np.int64)
    for l, r in enumerate(rows):
        out[l, :len(r)] = r
    return out


def _rotvec_matrix(v):
    from femcheck.kinematics.frames import rotvec_to_matrix
    return rotvec_to_matrix(np.asarray(v, float))


def _home_twists(leg) -> np.ndarray:
    """(nd, 6) unit twists of the leg's freedoms at its last centre, home configuration."""
    C = leg.centres[-1]
    out = np.zeros((leg.n_dof, 6))
    for k in range(leg.n_dof):
        w = leg.dof_axis[k]
        out[k] = np.r_[np.cross(w, C - leg.dof_point[k]), w] if leg.dof_kind[k] == "R" else np.r_[w, 0, 0, 0]
    return out
