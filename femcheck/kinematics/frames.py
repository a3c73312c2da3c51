"""Small-displacement frame algebra for wrenches and twists (seed 000 eqs. 2-12; docs/conventions.md §1, §4).

Wrench ``W = [F; M]`` and twist ``t = [d; theta]`` are 6-vectors, force/translation first. All
functions are vectorized: leading axes broadcast, the last one or two axes are the 3- or 6-vectors.
"""
from __future__ import annotations

import numpy as np


def skew(r: np.ndarray) -> np.ndarray:
    """[r x]: (..., 3) -> (..., 3, 3) with skew(r) @ v == cross(r, v) (seed 000 eq. 6)."""
    r = np.asarray(r, dtype=float)
    out = np.zeros(r.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -r[..., 2], r[..., 1]
    out[..., 1, 0], out[..., 1, 2] = r[..., 2], -r[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -r[..., 1], r[..., 0]
    return out


def wrench_shift(r: np.ndarray) -> np.ndarray:
    """Jf(r) (..., 6, 6): moves a wrench from point Q to point P with r = Q - P.

    ``W_P = Jf(Q - P) W_Q``, i.e. ``M_P = M_Q + (Q - P) x F`` (the paper's J_force, seed 000 eq. 5).
    Its transpose moves twists the other way: ``t_Q = Jf(Q - P)^T t_P`` (``d_Q = d_P + theta x (Q - P)``).
    """
    r = np.asarray(r, dtype=float)
    out = np.zeros(r.shape[:-1] + (6, 6))
    out[..., 0, 0] = out[..., 1, 1] = out[..., 2, 2] = 1.0
    out[..., 3, 3] = out[..., 4, 4] = out[..., 5, 5] = 1.0
    out[..., 3:, :3] = skew(r)
    return out


def twist_shift(r: np.ndarray) -> np.ndarray:
    """Jf(r)^T (..., 6, 6): twist at P -> twist at Q for r = Q - P (seed 000 eq. 9 J_disp = Jf(B - C)^T)."""
    return np.swapaxes(wrench_shift(r), -1, -2)


def rot6(R: np.ndarray) -> np.ndarray:
    """Rot(R) = blockdiag(R, R): (..., 3, 3) -> (..., 6, 6) (seed 000 eqs. 11-12)."""
    R = np.asarray(R, dtype=float)
    out = np.zeros(R.shape[:-2] + (6, 6))
    out[..., :3, :3] = R
    out[..., 3:, 3:] = R
    return out


def rotate_compliance(R: np.ndarray, S_local: np.ndarray) -> np.ndarray:
    """S_U = Rot(R) S_L Rot(R)^T for a 6x6 compliance or stiffness given in the frame with axes R (columns in U)."""
    Q = rot6(R)
    return Q @ S_local @ np.swapaxes(Q, -1, -2)


def rotvec_to_matrix(rv: np.ndarray) -> np.ndarray:
    """Rotation vector (..., 3) rad -> rotation matrix (..., 3, 3) (Rodrigues), exact at zero."""
    rv = np.asarray(rv, dtype=float)
    if not rv.any():  # the common case of test poses: platform parallel to the base
        return np.broadcast_to(np.eye(3), rv.shape[:-1] + (3, 3)).copy()
    th = np.linalg.norm(rv, axis=-1)[..., None, None]
    K = skew(rv)
    small = th < 1e-8
    th_safe = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th**2 / 6.0, np.sin(th_safe) / th_safe)
    b = np.where(small, 0.5 - th**2 / 24.0, (1.0 - np.cos(th_safe)) / th_safe**2)
    return np.eye(3) + a * K + b * (K @ K)


def rpy_deg_to_matrix(rpy_deg) -> np.ndarray:
    """Roll-pitch-yaw (deg, fixed axes x then y then z: R = Rz Ry Rx) -> (3, 3)."""
    r, p, y = np.deg2rad(np.asarray(rpy_deg, dtype=float))
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def matrix_to_rotvec(R: np.ndarray) -> np.ndarray:
    """Rotation matrix (..., 3, 3) -> rotation vector (..., 3) rad (for angles below pi)."""
    R = np.asarray(R, dtype=float)
    cos = np.clip((np.trace(R, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    th = np.arccos(cos)
    w = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], -1)
    s = np.sin(th)
    factor = np.where(th < 1e-8, 0.5, th / (2.0 * np.where(s == 0, 1.0, s)))
    return w * factor[..., None]


def guideway_frames(case) -> np.ndarray:
    """(6, 3, 3) guideway frames A_i: columns x_A (radial, orthogonal to e), y_A = e x x_A, z_A = e."""
    e = np.asarray(case.geometry.guideway_direction, dtype=float)
    th = case.base_angles_rad
    radial = np.stack([np.cos(th), np.sin(th), np.zeros(6)], axis=1)
    x = radial - (radial @ e)[:, None] * e
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = np.cross(e, x)
    return np.stack([x, y, np.broadcast_to(e, x.shape)], axis=-1)


def link_frames(u: np.ndarray) -> np.ndarray:
    """(..., 3, 3) link frames B_i: z_B = u, x_B = (-u_y, u_x, 0)/|.|, y_B = z_B x x_B (seed 000 eq. 20)."""
    x = np.stack([-u[..., 1], u[..., 0], np.zeros(u.shape[:-1])], axis=-1)
    x /= np.linalg.norm(x, axis=-1, keepdims=True)
    return np.stack([x, np.cross(u, x), u], axis=-1)
