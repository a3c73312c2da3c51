"""Numeric inverse kinematics and joint twists of any leg set, vectorized over poses (one Python loop over legs).

Each leg is a product of exponentials of its one-freedom screws at the home pose: an R freedom with axis w
through c moves by ``[Rot(w, q), (I - Rot(w, q)) c]``, a P freedom by ``[I, u q]``; the leg's end frame is the
platform frame placed at the leg's last joint centre. Given platform poses, Gauss-Newton on the end frame
(position of the attachment point C and the rotation vector of the orientation error) with the least-squares
step ``dq = pinv(J) e`` finds the joint values from q = 0 (the home pose) for every pose at once; a leg with
fewer than six freedoms (e.g. R-U-U) is solved in the least-squares sense and counted as reaching the pose
only where the residual vanishes.

Twists are ``[d; theta]`` at C in the base frame: an R freedom contributes ``[w x (C - c); w]``, a P freedom
``[u; 0]`` (its unit joint twist; ``femcheck.kinematics.frames`` conventions).
"""
from __future__ import annotations


import numpy as np

from femcheck.kinematics.frames import matrix_to_rotvec, rotvec_to_matrix
from femcheck.parallel.leg_state import DeviceState, LegState  # noqa: F401  (the states this module returns)

#: Gauss-Newton iterations and the residual (m and rad) below which a pose counts as reached
MAX_ITER = 60
TOL = 1e-11
#: largest change of one joint value in one step (rad or m)
MAX_STEP = 0.3


def _prefixes(leg, q):
    """Transforms (R (n, nd+1, 3, 3), t (n, nd+1, 3)) of the freedoms before each dof (index nd: all of them)."""
    n, nd = q.shape
    R = np.empty((n, nd + 1, 3, 3))
    t = np.empty((n, nd + 1, 3))
    R[:, 0], t[:, 0] = np.eye(3), 0.0
    for k in range(nd):
        w = leg.dof_axis[k]
        if leg.dof_kind[k] == "R":
            Rk = rotvec_to_matrix(w[None, :] * q[:, k:k + 1])
            tk = leg.dof_point[k] - Rk @ leg.dof_point[k]
        else:
            Rk = np.broadcast_to(np.eye(3), (n, 3, 3))
            tk = w[None, :] * q[:, k:k + 1]
        R[:, k + 1] = R[:, k] @ Rk
        t[:, k + 1] = np.einsum("nij,nj->ni", R[:, k], tk) + t[:, k]
    return R, t


def _twists(leg, R, t, C):
    """(n, nd, 6) unit twists of the freedoms at C (their screws moved by the freedoms before them)."""
    w = np.einsum("nkij,kj->nki", R[:, :-1], leg.dof_axis)
    c = np.einsum("nkij,kj->nki", R[:, :-1], leg.dof_point) + t[:, :-1]
    rev = np.array([k == "R" for k in leg.dof_kind])
    d = np.where(rev[None, :, None], np.cross(w, C[:, None, :] - c), w)
    return np.concatenate([d, np.where(rev[None, :, None], w, 0.0)], axis=-1)


def solve_leg(leg, R_home, R_target, C_target) -> LegState:
    """Inverse kinematics of one leg: platform orientations R_target (n, 3, 3), attachment points C_target (n, 3)."""
    n = C_target.shape[0]
    q = np.zeros((n, leg.n_dof))
    c_last = leg.centres[-1]
    for _ in range(MAX_ITER):
        R, t = _prefixes(leg, q)
        C = R[:, -1] @ c_last + t[:, -1]
        e = np.concatenate([C_target - C, matrix_to_rotvec(R_target @ np.swapaxes(R[:, -1] @ R_home, -1, -2))], -1)
        res = np.linalg.norm(e, axis=1)
        active = (res > TOL * 1e-2) & np.isfinite(res)
        if not active.any():
            break
        J = np.swapaxes(_twists(leg, R, t, C), -1, -2)
        dq = np.einsum("nij,nj->ni", np.linalg.pinv(J[active], rcond=1e-10), e[active])
        # limit the step (a far-off pose must not throw the leg through a singularity into NaN)
        dq *= np.minimum(1.0, MAX_STEP / np.maximum(np.abs(dq).max(axis=1, keepdims=True), 1e-300))
        q[active] += dq
    R, t = _prefixes(leg, q)
    C = R[:, -1] @ c_last + t[:, -1]
    e = np.concatenate([C_target - C, matrix_to_rotvec(R_target @ np.swapaxes(R[:, -1] @ R_home, -1, -2))], -1)
    res = np.linalg.norm(e, axis=1)
    first = np.array([leg.dofs_before(int(np.flatnonzero(leg.joint_centre == m)[0])) for m in range(len(leg.centres))])
    centres = np.einsum("nmij,mj->nmi", R[:, first], leg.centres) + t[:, first]
    centres[:, -1] = C
    link_R = np.empty((n, len(leg.links), 3, 3))
    link_len = np.empty((n, len(leg.links)))
    for m, ln in enumerate(leg.links):
        d = centres[:, ln.end] - centres[:, ln.start]
        link_len[:, m] = np.linalg.norm(d, axis=1)
        z = d / link_len[:, m, None]
        body = leg.dofs_through(int(np.flatnonzero(leg.joint_centre == ln.start)[0]))  # after the start joint
        x = R[:, body] @ ln.x_axis
        x = x - np.einsum("ni,ni->n", x, z)[:, None] * z
        x /= np.linalg.norm(x, axis=1, keepdims=True)
        link_R[:, m] = np.stack([x, np.cross(z, x), z], axis=-1)
    ok = res < TOL
    for d, lo, hi in leg.limits:
        ok &= (q[:, d] >= lo) & (q[:, d] <= hi)
    return LegState(q=q, ok=ok, residual=res, C=C, centres=centres, twists=_twists(leg, R, t, C),
                    link_R=link_R, link_length=link_len)


def as_poses(poses) -> np.ndarray:
    """TCP poses as a C-contiguous float (n, 6) array [x, y, z, rx, ry, rz] (m, rad); ValueError otherwise."""
    P = np.atleast_2d(np.asarray(poses, dtype=float))
    if P.ndim != 2 or P.shape[1] != 6 or not np.all(np.isfinite(P)):
        raise ValueError(f"poses: expected finite (n, 6) [x, y, z, rx, ry, rz] in m and rad, got shape {P.shape}")
    return np.ascontiguousarray(P)


def solve_legs(device, poses, backend: str = "compiled") -> DeviceState:
    """Inverse kinematics of every leg at TCP poses (n, 6) [x, y, z, rx, ry, rz] (m, rad).

    ``backend``: "compiled" (default; :mod:`femcheck.parallel.chain_kernel`: closed forms where a leg has one,
    the same Gauss-Newton otherwise) or "numpy" (this module, the reference).
    """
    from femcheck.parallel.compiled import check_backend, solve_legs_compiled
    check_backend(backend)
    P = as_poses(poses)
    if backend == "compiled":
        return solve_legs_compiled(device, np.ascontiguousarray(P))
    R = rotvec_to_matrix(P[:, 3:])
    origin = P[:, :3] - R @ device.tcp_offset
    R_home = rotvec_to_matrix(device.home_pose[3:])
    legs = tuple(solve_leg(leg, R_home, R, origin + R @ leg.b_platform) for leg in device.legs)
    return DeviceState(poses=P, tcp=P[:, :3], R=R, legs=legs)


def null_basis(A: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """(n, 6, m) orthonormal basis of the wrenches W with A^T W = 0 for A (n, 6, k) (the rank is taken from
    the first pose, so that every pose has the same m)."""
    if A.shape[-1] == 0:
        return np.broadcast_to(np.eye(6), A.shape[:-2] + (6, 6)).copy()
    U, s, _ = np.linalg.svd(A)
    rank = int(np.sum(s[0] > tol * s[0, 0]))
    return U[:, :, rank:]


def released_wrenches(leg, state: LegState) -> np.ndarray:
    """(n, 6, m) basis of the wrenches at C the leg can carry with its passive freedoms free (reciprocal to them)."""
    return null_basis(np.swapaxes(state.twists[:, leg.passive_dofs, :], -1, -2))


def actuation_jacobian(device, state: DeviceState) -> np.ndarray:
    """(n, n_legs, 6) rows with q_dot_act,i = row_i . [v_T; omega]: the inverse velocity Jacobian of the actuated joints.

    Row i is the leg's actuation wrench (reciprocal to its passive freedoms, unit work on the actuated one)
    carried to the TCP. For a 6-UPS hexapod it is ``[u_i; (C_i - T) x u_i]``.
    """
    rows = []
    for i, leg in enumerate(device.legs):
        s = state.legs[i]
        N = released_wrenches(leg, s)
        xi = s.twists[:, leg.actuated_dof, :]
        a = np.einsum("nim,ni->nm", N, xi)
        zeta = np.einsum("nim,nm->ni", N, a) / np.einsum("nm,nm->n", a, a)[:, None]
        rows.append(np.einsum("nij,ni->nj", state.G(i), zeta))  # wrench at C -> at T is G^T zeta; row = zeta^T G
    return np.stack(rows, axis=1)


def constraint_rank(device, poses) -> tuple[int, np.ndarray]:
    """Rank of the wrenches all legs can carry with released joints at the first pose, and a free platform
    twist (TCP, [d; theta]) when the rank is below 6 (zeros otherwise)."""
    state = solve_legs(device, poses)
    cols = [np.einsum("nji,njm->nim", state.G(i), released_wrenches(leg, state.legs[i]))[0]
            for i, leg in enumerate(device.legs)]
    A = np.concatenate(cols, axis=1)
    U, s, _ = np.linalg.svd(A)
    rank = int(np.sum(s > 1e-9 * s[0]))
    return rank, (U[:, -1] if rank < 6 else np.zeros(6))
