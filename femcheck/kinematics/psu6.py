"""6-PSU inverse kinematics, test points and Jacobian (seed 000 §4; docs/conventions.md §2-3, §8).

Poses are TCP poses ``[x, y, z, rx, ry, rz]`` (m, rad; rotation vector of the platform frame P in U),
shape (n, 6). Everything is vectorized over poses; chains (legs) i = 0..5 are the second axis.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.errors import UnreachablePoseError
from femcheck.kinematics.frames import rotvec_to_matrix, rpy_deg_to_matrix, matrix_to_rotvec

POINT_LABELS = tuple(f"P{k}" for k in range(9))


@dataclasses.dataclass(frozen=True)
class LegGeometry:
    """Inverse-kinematics result for n poses (all SI, frame U).

    A: (6, 3) guideway clamp points; B: (n, 6, 3) ball centres (slider); C: (n, 6, 3) U-joint centres;
    u: (n, 6, 3) link unit vectors B -> C; slider: (n, 6) guideway cantilever lengths s_i;
    tcp: (n, 3); R_platform: (n, 3, 3); platform_centre: (n, 3); e: (3,) rail direction.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    u: np.ndarray
    slider: np.ndarray
    tcp: np.ndarray
    R_platform: np.ndarray
    platform_centre: np.ndarray
    e: np.ndarray

    @property
    def n(self) -> int:
        return self.B.shape[0]


def as_poses(poses) -> np.ndarray:
    """Validate poses to a float (n, 6) array (a single (6,) pose becomes (1, 6))."""
    p = np.asarray(poses, dtype=float)
    if p.ndim == 1:
        p = p[None, :]
    if p.ndim != 2 or p.shape[1] != 6:
        raise ValueError(f"poses: expected shape (n, 6) [x, y, z, rx, ry, rz] in m and rad, got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("poses: contain NaN or inf")
    return p


def test_points(case) -> np.ndarray:
    """(9, 6) TCP poses of the test cube: P0 = nominal, P1..P8 = P0 + edge/2 * corner_signs (docs/conventions.md §8).

    Orientation: the case's ``platform_rpy_deg`` (the same at every point), as a rotation vector.
    """
    w = case.workspace
    centre = np.asarray(w.nominal_tcp_m, dtype=float)
    corners = centre + 0.5 * w.cube_edge_m * np.asarray(w.corner_signs, dtype=float)
    pos = np.vstack([centre, corners])
    rv = matrix_to_rotvec(rpy_deg_to_matrix(case.geometry.platform_rpy_deg))
    return np.hstack([pos, np.tile(rv, (9, 1))])


def leg_geometry(case, poses, labels=None, check_reach: bool = True) -> LegGeometry:
    """Inverse kinematics: TCP poses -> slider positions and joint points of the six chains.

    With ``d_i = C_i - A_i``: ``s_i = d_i.e - sqrt(L2^2 - |d_i - (d_i.e) e|^2)`` (slider below C_i).
    Reachable iff the root is real and ``min_slider_position_m < s_i < rail_length_m``; otherwise
    :class:`UnreachablePoseError` names the first failing pose (``labels[k]`` or its index and values)
    and chain. ``check_reach=False`` returns NaN for unreachable chains instead (for maps).
    """
    p = as_poses(poses)
    g = case.geometry
    e = np.asarray(g.guideway_direction, dtype=float)
    L2 = g.proximal_link_length_m
    R = rotvec_to_matrix(p[:, 3:])
    tcp = p[:, :3]
    centre = tcp - R @ np.asarray(g.tcp_offset_m)
    C = centre[:, None, :] + np.einsum("nij,kj->nki", R, case.platform_points)
    A = case.base_points
    d = C - A[None]
    de = d @ e
    perp = d - de[..., None] * e
    disc = L2**2 - np.einsum("nki,nki->nk", perp, perp)
    with np.errstate(invalid="ignore"):
        s = de - np.sqrt(disc)
    bad = ~(disc >= 0) | ~(s > g.min_slider_position_m) | ~(s < g.rail_length_m)
    if check_reach and bad.any():
        k, i = np.argwhere(bad)[0]
        label = labels[k] if labels is not None else f"#{k} {np.array2string(p[k], precision=4)}"
        if not disc[k, i] >= 0:
            why = f"the link (L2 = {L2} m) cannot span the {np.sqrt(max(L2**2 - disc[k, i], 0)):.4f} m horizontal offset"
        else:
            why = f"slider position s = {s[k, i]:.4f} m outside ({g.min_slider_position_m}, {g.rail_length_m}) m"
        raise UnreachablePoseError(str(label), int(i), why)
    s = np.where(bad, np.nan, s)
    B = A[None] + s[..., None] * e
    u = (C - B) / L2
    return LegGeometry(A=A, B=B, C=C, u=u, slider=s, tcp=tcp, R_platform=R, platform_centre=centre, e=e)


def forward_residual(case, legs: LegGeometry) -> np.ndarray:
    """(n, 6) link-length closure error |C_i - B_i| - L2 (m): the forward check of an IK solution."""
    return np.linalg.norm(legs.C - legs.B, axis=-1) - case.geometry.proximal_link_length_m


def jacobian(case, legs: LegGeometry) -> np.ndarray:
    """(n, 6, 6) velocity Jacobian ``s_dot = J [v_T; omega]``; row i = [u_i^T, ((C_i - T) x u_i)^T] / (u_i . e)."""
    r = legs.C - legs.tcp[:, None, :]
    rows = np.concatenate([legs.u, np.cross(r, legs.u)], axis=-1)
    return rows / (legs.u @ legs.e)[..., None]


def condition_number(case, legs: LegGeometry) -> np.ndarray:
    """(n,) cond(J_h), J_h = J diag(I3, I3 / L_char), L_char = R_p (docs/conventions.md §3)."""
    J = jacobian(case, legs).copy()
    J[..., 3:] /= case.geometry.platform_radius_m
    sv = np.linalg.svd(J, compute_uv=False)
    return sv[..., 0] / sv[..., -1]


def forward_kinematics(case, slider: np.ndarray, guess_poses, iterations: int = 50, tol: float = 1e-13) -> np.ndarray:
    """Forward kinematics by Newton iteration on the IK, vectorized: slider (n, 6) m -> poses (n, 6).

    Uses the Jacobian above (translation + small rotation vector update). Converges from a guess
    within the same assembly mode (e.g. the nominal pose).
    """
    slider = np.atleast_2d(np.asarray(slider, dtype=float))
    poses = np.array(np.broadcast_to(as_poses(guess_poses), (slider.shape[0], 6)))
    for _ in range(iterations):
        legs = leg_geometry(case, poses, check_reach=False)
        r = slider - legs.slider
        if np.nanmax(np.abs(r)) < tol:
            break
        step = np.linalg.solve(jacobian(case, legs), r[..., None])[..., 0]
        R_new = rotvec_to_matrix(step[:, 3:]) @ legs.R_platform
        poses = np.hstack([poses[:, :3] + step[:, :3], matrix_to_rotvec(R_new)])
    return poses
