"""Denavit-Hartenberg serial chains: forward kinematics and the geometric Jacobian at the tool point.

Two conventions (declared per case, ``convention = "standard" | "modified"``):

* **standard** (Denavit-Hartenberg 1955, Spong): row i holds (a_i, alpha_i, d_i, theta_i) and
  ``T_{i-1,i} = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``; joint i turns about z_{i-1}.
* **modified** (Craig 1986; seed 003 eq. 1, seed 002 "DHm"): row i holds (a_{i-1}, alpha_{i-1}, d_i, theta_i) and
  ``T_{i-1,i} = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i)``; joint i turns about z_i.

The joint angle is ``theta_i = q_i + theta_offset_i``. All joints are revolute. The tool point (TCP) is
``tool_offset_m`` written in the last frame (flange). Everything is vectorized over poses: ``q`` is
``(m, n)`` (or ``(n,)``, treated as m = 1) in rad, lengths in m.

The geometric Jacobian (seed 003 eqs. 4-6) maps joint rates to the TCP twist ``[v; omega]`` in the
base frame: column j is ``[z_j x (p - o_j); z_j]`` for a revolute joint with axis z_j through o_j.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Literal

import numpy as np

log = logging.getLogger(__name__)

Convention = Literal["standard", "modified"]


@dataclass(frozen=True)
class DHChain:
    """An immutable serial chain of revolute joints described by a DH table.

    Attributes (each a tuple of n floats, SI): ``a_m``, ``alpha_rad``, ``d_m``, ``theta_offset_rad``;
    ``convention``; ``tool_offset_m`` (3,) TCP in the last frame, m; ``base`` (4, 4) pose of frame 0
    in the world (identity by default).
    """

    a_m: tuple[float, ...]
    alpha_rad: tuple[float, ...]
    d_m: tuple[float, ...]
    theta_offset_rad: tuple[float, ...]
    convention: Convention = "standard"
    tool_offset_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    base: tuple[tuple[float, ...], ...] = ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 0.0, 1.0))

    def __post_init__(self):
        n = len(self.a_m)
        if not (len(self.alpha_rad) == len(self.d_m) == len(self.theta_offset_rad) == n) or n == 0:
            raise ValueError("DH table columns must have the same, non-zero length")
        if self.convention not in ("standard", "modified"):
            raise ValueError(f"convention {self.convention!r}; expected 'standard' or 'modified'")

    @property
    def n_joints(self) -> int:
        return len(self.a_m)


@dataclass(frozen=True)
class ChainPoses:
    """Forward kinematics of m poses of a chain.

    ``frames`` (m, n+1, 4, 4): frames 0..n in the world; ``joint_frames`` (m, n, 4, 4): for each joint a
    frame whose z is the joint axis, whose origin lies on it and which turns with the joint (standard:
    ``T_{i-1} Rz(theta_i)``; modified: ``T_i``); ``tcp`` (m, 3) tool point, m.
    """

    frames: np.ndarray
    joint_frames: np.ndarray
    tcp: np.ndarray

    @property
    def axes(self) -> np.ndarray:
        """(m, n, 3) unit joint axes z_j in the world."""
        return self.joint_frames[..., :3, 2]

    @property
    def origins(self) -> np.ndarray:
        """(m, n, 3) a point o_j on each joint axis, m."""
        return self.joint_frames[..., :3, 3]


def _rot_z(theta: np.ndarray) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    T = np.zeros(theta.shape + (4, 4))
    T[..., 0, 0], T[..., 0, 1], T[..., 1, 0], T[..., 1, 1] = c, -s, s, c
    T[..., 2, 2] = T[..., 3, 3] = 1.0
    return T


def _screw_x(a: float, alpha: float) -> np.ndarray:
    """Tx(a) Rx(alpha) (= Rx(alpha) Tx(a), they commute)."""
    c, s = np.cos(alpha), np.sin(alpha)
    return np.array([[1.0, 0, 0, a], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _trans_z(d: float) -> np.ndarray:
    T = np.eye(4)
    T[2, 3] = d
    return T


def as_poses(chain: DHChain, q) -> np.ndarray:
    """Joint angles as an (m, n) float array, rad; raises ValueError on a wrong width."""
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:
        q = q[None, :]
    if q.ndim != 2 or q.shape[1] != chain.n_joints:
        raise ValueError(f"joint angles have shape {q.shape}; expected (m, {chain.n_joints})")
    return q


def forward_kinematics(chain: DHChain, q) -> ChainPoses:
    """Frames, joint frames and the tool point for poses ``q`` (m, n) rad (seed 003 eqs. 1-2).

    One matrix product per joint, each vectorized over the m poses.
    """
    q = as_poses(chain, q)
    m, n = q.shape
    theta = q + np.asarray(chain.theta_offset_rad)
    frames = np.empty((m, n + 1, 4, 4))
    joint_frames = np.empty((m, n, 4, 4))
    T = np.broadcast_to(np.asarray(chain.base, dtype=float), (m, 4, 4)).copy()
    frames[:, 0] = T
    for i in range(n):
        Rz = _rot_z(theta[:, i])
        if chain.convention == "standard":
            J = T @ Rz
            joint_frames[:, i] = J
            T = J @ (_trans_z(chain.d_m[i]) @ _screw_x(chain.a_m[i], chain.alpha_rad[i]))
        else:
            T = (T @ _screw_x(chain.a_m[i], chain.alpha_rad[i])) @ Rz @ _trans_z(chain.d_m[i])
            joint_frames[:, i] = T
        frames[:, i + 1] = T
    tcp = (T @ np.append(np.asarray(chain.tool_offset_m, dtype=float), 1.0))[:, :3]
    return ChainPoses(frames=frames, joint_frames=joint_frames, tcp=tcp)


def screw_jacobian(axes: np.ndarray, origins: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Geometric Jacobian of revolute (virtual) joints at ``point``.

    ``axes``, ``origins`` (m, k, 3); ``point`` (m, 3). Returns (m, 6, k): column j is
    ``[u_j x (p - o_j); u_j]`` (twist at p, translation first).
    """
    lever = point[:, None, :] - origins
    v = np.cross(axes, lever)
    return np.concatenate([v, axes], axis=-1).transpose(0, 2, 1)


def geometric_jacobian(chain: DHChain, q) -> np.ndarray:
    """(m, 6, n) geometric Jacobian at the tool point, base frame (seed 003 eqs. 4-6)."""
    fk = forward_kinematics(chain, q)
    return screw_jacobian(fk.axes, fk.origins, fk.tcp)
