"""Kinematic trees of revolute and prismatic DH rows: forward kinematics with geometric corrections and elastic
deflections.

A :class:`RobotTree` is the array form of a ``serial_tree`` case (rows in an order where every parent comes
first). Everything is vectorized over the m poses; the only Python loop runs over the rows (the tree's depth
order), never over poses.

Row transform (the convention is the case's):

* standard: ``T_i = T_parent S_i Rz(theta_i) [tilt_i] Tz(d_i) Tx(a_i) Rx(alpha_i)``, joint frame
  ``T_parent S_i Rz(theta_i) [tilt_i]``;
* modified (Craig): ``T_i = T_parent S_i Rx(alpha_i) Tx(a_i) Rz(theta_i) [tilt_i] Tz(d_i)``, joint frame up to the
  tilt;

with ``theta_i = q_i + offset_i + dtheta_i``, ``S_i`` the static frame, ``[tilt_i]`` the small rotation of the
two tilt springs about the joint frame's x and y (seed 002's extended VJM), and, after the row, the rigid
motion of the row's link tip when the link bends (Euler-Bernoulli cantilever under its tip load).

A prismatic row slides instead: ``theta_i = offset_i + dtheta_i`` and ``d_i + q_i``. Its joint frame is the
carriage, ``T_parent S_i Rz(theta_i) Tz(d_i + q_i)`` (standard; modified: ``T_parent S_i Rx(alpha_i) Tx(a_i)
Rz(theta_i) Tz(d_i + q_i)``), and the tilt (springs and guide play of the moving stage) turns the rest of the row
about the carriage: ``T_i = J_i [tilt_i] Tx(a_i) Rx(alpha_i)`` (standard) or ``J_i [tilt_i]`` (modified).
"""
from __future__ import annotations

import dataclasses

import numpy as np

#: geometric corrections per DH row, in this order (rad, m, m, rad)
ROW_PARAMS = ("theta", "d", "a", "alpha")
#: corrections of a declared static frame: origin (m) and a small rotation vector (rad)
STATIC_PARAMS = ("x", "y", "z", "rx", "ry", "rz")


def rotation(rvec: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of rotation vectors (..., 3) rad (Rodrigues, exact at any angle)."""
    rvec = np.asarray(rvec, dtype=float)
    th = np.linalg.norm(rvec, axis=-1)
    small = th < 1e-12
    k = rvec / np.where(small, 1.0, th)[..., None]
    K = np.zeros(rvec.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -k[..., 2], k[..., 1], -k[..., 0]
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = k[..., 2], -k[..., 1], k[..., 0]
    s, c = np.sin(th)[..., None, None], np.cos(th)[..., None, None]
    return np.eye(3) + s * K + (1 - c) * (K @ K)


def rpy_matrix(rpy_rad) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll) (roll, pitch, yaw about fixed x, y, z)."""
    r, p, y = rpy_rad
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _rz(theta):
    c, s = np.cos(theta), np.sin(theta)
    T = np.zeros(theta.shape + (4, 4))
    T[..., 0, 0], T[..., 0, 1], T[..., 1, 0], T[..., 1, 1] = c, -s, s, c
    T[..., 2, 2] = T[..., 3, 3] = 1.0
    return T


def _screw_x(a, alpha):
    """Tx(a) Rx(alpha) (they commute); scalars or arrays."""
    a, alpha = np.broadcast_arrays(np.asarray(a, float), np.asarray(alpha, float))
    c, s = np.cos(alpha), np.sin(alpha)
    T = np.zeros(a.shape + (4, 4))
    T[..., 0, 0] = 1.0
    T[..., 1, 1], T[..., 1, 2], T[..., 2, 1], T[..., 2, 2] = c, -s, s, c
    T[..., 0, 3] = a
    T[..., 3, 3] = 1.0
    return T


def _tz(d):
    d = np.asarray(d, float)
    T = np.zeros(d.shape + (4, 4))
    T[..., 0, 0] = T[..., 1, 1] = T[..., 2, 2] = T[..., 3, 3] = 1.0
    T[..., 2, 3] = d
    return T


def homogeneous(R: np.ndarray, p: np.ndarray) -> np.ndarray:
    T = np.zeros(np.broadcast_shapes(R.shape[:-2], p.shape[:-1]) + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = p
    T[..., 3, 3] = 1.0
    return T


@dataclasses.dataclass(frozen=True, eq=False)
class RobotTree:
    """Array form of a kinematic tree (n rows, n_ind independent joints, n_mk markers). SI units.

    ``parent`` (n,) row index or -1 (base); ``coupling`` (n, n_ind): q_rows = coupling @ q_ind;
    ``independent`` (n_ind,) rows that own a CSV column; ``descendant`` (n, n) D[j, b] = b is j or below j;
    ``prismatic`` (n,) bool; ``compliance_torsion`` (n,) per row, along the row's joint coordinate (rad/(N m) on
    revolute rows, m/N axial on prismatic ones): an independent row's drive spring, a coupled row's own spring (in
    series with its coupling); ``guide_overlap`` (n,) m guide engagement at q = 0 (nan: not stated),
    ``guide_clearance`` (n,) m nominal diametral guide clearance, ``compliance_tilt`` (n, 2), ``compliance_bending`` (n,) nominal (1/k, 0 = rigid); ``marker_link`` (n_mk,), ``marker_offset`` (n_mk, 3); ``payload_link`` (-1 none).
    """

    names: tuple[str, ...]
    branch: tuple[str, ...]
    size: tuple[str, ...]
    convention: str
    parent: np.ndarray
    a: np.ndarray
    alpha: np.ndarray
    d: np.ndarray
    theta_offset: np.ndarray
    static: np.ndarray            # (n, 4, 4) nominal static frames
    has_static: np.ndarray        # (n,) bool: the case declares a static frame (its corrections are fitted)
    coupling: np.ndarray
    independent: np.ndarray
    prismatic: np.ndarray
    guide_overlap: np.ndarray
    guide_clearance: np.ndarray
    mass: np.ndarray
    com: np.ndarray
    compliance_torsion: np.ndarray
    compliance_tilt: np.ndarray
    compliance_bending: np.ndarray
    backlash: np.ndarray          # (n_ind,) rad, 0 = none
    backlash_width: np.ndarray    # (n_ind,) N m, nan = the diagnosis' default
    marker_names: tuple[str, ...]
    marker_link: np.ndarray
    marker_offset: np.ndarray
    payload_link: int
    payload_com: np.ndarray
    gravity: np.ndarray
    descendant: np.ndarray

    @property
    def n_rows(self) -> int:
        return len(self.names)

    @property
    def n_joints(self) -> int:
        """Independent joints (CSV q columns)."""
        return len(self.independent)

    @property
    def coupled(self) -> np.ndarray:
        """(n,) bool: rows that follow others through ``coupling`` (no CSV column)."""
        out = np.ones(self.n_rows, bool)
        out[self.independent] = False
        return out

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(self.names[i] for i in self.independent)

    @classmethod
    def from_case(cls, case) -> "RobotTree":
        J = case.joints
        n = len(J)
        index = {j.name: i for i, j in enumerate(J)}
        parent = np.array([-1 if j.parent == "base" else index[j.parent] for j in J])
        indep = np.array([i for i, j in enumerate(J) if j.coupling is None])
        col = {int(r): c for c, r in enumerate(indep)}
        E = np.zeros((n, len(indep)))
        for i, j in enumerate(J):
            if j.coupling is None:
                E[i, col[i]] = 1.0
            else:
                for k, c in j.coupling.items():
                    E[i, col[index[k]]] += c
        static = np.stack([homogeneous(rpy_matrix(np.deg2rad(j.static_rpy_deg)), np.asarray(j.static_origin_m)) for j in J])
        has_static = np.array([any(j.static_origin_m) or any(j.static_rpy_deg) for j in J])
        D = np.eye(n, dtype=bool)
        for i in range(n - 1, -1, -1):     # children come after parents: accumulate bottom-up
            if parent[i] >= 0:
                D[parent[i]] |= D[i]
        inv = lambda k: 0.0 if k is None else 1.0 / k
        ct = np.array([inv(j.axial_stiffness_N_per_m if j.type == "prismatic" else j.stiffness_Nm_per_rad) for j in J])
        ctilt = np.array([[inv(k) for k in (j.tilt_stiffness_Nm_per_rad or (None, None))] for j in J])
        cb = np.array([inv(j.bending_EI_Nm2) for j in J])
        pl = -1 if case.payload is None else index[case.payload.link]
        return cls(names=tuple(j.name for j in J), branch=tuple(j.branch for j in J), size=tuple(j.size for j in J),
                   convention=case.kinematics.convention, parent=parent,
                   a=np.array([j.a_m for j in J]), alpha=np.deg2rad([j.alpha_deg for j in J]),
                   d=np.array([j.d_m for j in J]), theta_offset=np.deg2rad([j.theta_offset_deg for j in J]),
                   static=static, has_static=has_static, coupling=E, independent=indep,
                   prismatic=np.array([j.type == "prismatic" for j in J]),
                   guide_overlap=np.array([np.nan if j.guide_overlap_m is None else j.guide_overlap_m for j in J]),
                   guide_clearance=np.array([j.guide_clearance_m or 0.0 for j in J]),
                   mass=np.array([j.mass_kg for j in J]), com=np.array([j.com_m for j in J], float),
                   compliance_torsion=ct, compliance_tilt=ctilt, compliance_bending=cb,
                   backlash=np.array([J[i].backlash_rad or 0.0 for i in indep]),
                   backlash_width=np.array([np.nan if J[i].backlash_torque_Nm is None else J[i].backlash_torque_Nm
                                            for i in indep]),
                   marker_names=tuple(m.name for m in case.markers),
                   marker_link=np.array([index[m.link] for m in case.markers]),
                   marker_offset=np.array([m.offset_m for m in case.markers], float),
                   payload_link=pl, payload_com=np.zeros(3) if case.payload is None else np.asarray(case.payload.com_m, float),
                   gravity=np.asarray(case.gravity.vector_m_per_s2, float), descendant=D)

    # ---- places ---------------------------------------------------------------------------------------
    def joint_place(self, rows) -> str:
        """Human name of a set of rows: 'joints 2-4 of right_arm (r2, r3, r4)', per branch, 1-based in the branch."""
        rows = sorted(int(r) for r in rows)
        if not rows:
            return ""
        by_branch: dict[str, list[int]] = {}
        for r in rows:
            by_branch.setdefault(self.branch[r], []).append(r)
        parts = []
        for b, rs in by_branch.items():
            in_branch = [i for i in range(self.n_rows) if self.branch[i] == b]
            pos = [in_branch.index(r) + 1 for r in rs]
            runs, start = [], pos[0]
            for k in range(1, len(pos) + 1):
                if k == len(pos) or pos[k] != pos[k - 1] + 1:
                    runs.append(f"{start}" if start == pos[k - 1] else f"{start}-{pos[k - 1]}")
                    if k < len(pos):
                        start = pos[k]
            word = "joint" if len(rs) == 1 else "joints"
            parts.append(f"{word} {', '.join(runs)} of {b} ({', '.join(self.names[r] for r in rs)})")
        return "; ".join(parts)


@dataclasses.dataclass(frozen=True)
class Geometry:
    """Corrections to the nominal geometry: ``row`` (n, 4) (dtheta, dd, da, dalpha); ``static`` (n, 6) (origin,
    rotation vector) of declared static frames; ``marker`` (n_mk, 3) offset corrections. Zeros = nominal."""

    row: np.ndarray
    static: np.ndarray
    marker: np.ndarray

    @classmethod
    def nominal(cls, tree: RobotTree) -> "Geometry":
        return cls(np.zeros((tree.n_rows, 4)), np.zeros((tree.n_rows, 6)), np.zeros((len(tree.marker_names), 3)))


@dataclasses.dataclass(frozen=True)
class TreePoses:
    """Forward kinematics of m poses: ``joint_frames`` (m, n, 4, 4) (z = joint axis, origin on it);
    ``frames`` (m, n, 4, 4) row frames; ``markers`` (m, n_mk, 3) m; ``link_root`` (m, n, 3) joint origins and
    ``link_tip`` (m, n, 3) row-frame origins before bending."""

    joint_frames: np.ndarray
    frames: np.ndarray
    markers: np.ndarray
    link_tip: np.ndarray

    @property
    def origins(self) -> np.ndarray:
        return self.joint_frames[..., :3, 3]


def forward(tree: RobotTree, q_rows: np.ndarray, geometry: Geometry | None = None, tilt: np.ndarray | None = None,
            bending: np.ndarray | None = None) -> TreePoses:
    """Frames and markers of poses ``q_rows`` (m, n) rad (every row's angle, coupled rows included).

    ``tilt`` (m, n, 2) rad: tilt-spring rotations about the joint frame's x and y; ``bending`` (m, n, 6): the
    link tip's rigid motion (translation m, rotation vector rad, world) applied about the tip.
    """
    g = geometry or Geometry.nominal(tree)
    m, n = q_rows.shape
    jf = np.empty((m, n, 4, 4))
    fr = np.empty((m, n, 4, 4))
    tip = np.empty((m, n, 3))
    eye = np.broadcast_to(np.eye(4), (m, 4, 4))
    for i in range(n):
        P = eye if tree.parent[i] < 0 else fr[:, tree.parent[i]]
        S = tree.static[i]
        if tree.has_static[i]:
            dS = homogeneous(rotation(g.static[i, 3:]), g.static[i, :3])
            S = S @ dS
        slide = bool(tree.prismatic[i])
        theta = tree.theta_offset[i] + g.row[i, 0] + (0.0 if slide else q_rows[:, i])
        d, a, al = tree.d[i] + g.row[i, 1], tree.a[i] + g.row[i, 2], tree.alpha[i] + g.row[i, 3]
        theta = np.broadcast_to(theta, (m,))
        if tree.convention == "standard":
            J = (P @ S) @ _rz(theta)
        else:
            J = (P @ (S @ _screw_x(a, al))) @ _rz(theta)
        if slide:                 # the joint frame is the carriage; the slide is done
            J = J @ _tz(d + q_rows[:, i])
        if tilt is not None:
            rv = np.zeros((m, 3))
            rv[:, :2] = tilt[:, i]
            J = J @ homogeneous(rotation(rv), np.zeros(3))
        if slide:
            T = J @ _screw_x(a, al) if tree.convention == "standard" else J
        else:
            T = J @ (_tz(d) @ _screw_x(a, al)) if tree.convention == "standard" else J @ _tz(d)
        tip[:, i] = T[:, :3, 3]
        if bending is not None:
            R = rotation(bending[:, i, 3:])
            p = T[:, :3, 3]
            B = homogeneous(R, p + bending[:, i, :3] - np.einsum("mij,mj->mi", R, p))
            T = B @ T
        jf[:, i], fr[:, i] = J, T
    off = np.append(tree.marker_offset + g.marker, np.ones((len(tree.marker_names), 1)), axis=1)   # (k, 4)
    mk = np.einsum("mkij,kj->mki", fr[:, tree.marker_link], off)[..., :3]
    return TreePoses(joint_frames=jf, frames=fr, markers=mk, link_tip=tip)


def gravity_wrenches(tree: RobotTree, fk: TreePoses, payload_kg: np.ndarray | None = None, mass_scale: float = 1.0,
                     strict: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Weight carried by each row: force F_j (m, n, 3) N and moment M_j (m, n, 3) N m about the joint origin.

    Bodies: each row's link (``mass`` x ``mass_scale`` at ``com`` in the row frame) and the payload
    (``payload_kg`` (m,) at ``payload_com``). ``strict``: only the bodies below the row (its link excluded),
    with the moment about the link tip (what the link's cantilever carries).
    """
    m = fk.frames.shape[0]
    com = np.einsum("mnij,nj->mni", fk.frames, np.append(tree.com, np.ones((tree.n_rows, 1)), axis=1))[..., :3]
    w = np.broadcast_to(tree.mass * mass_scale, (m, tree.n_rows))[..., None] * tree.gravity     # (m, n, 3)
    cw = np.cross(com, w)
    D = tree.descendant.astype(float)
    if strict:
        D = D - np.eye(tree.n_rows)
    F = np.einsum("jb,mbk->mjk", D, w)
    M0 = np.einsum("jb,mbk->mjk", D, cw)
    if tree.payload_link >= 0 and payload_kg is not None and np.any(payload_kg):
        pc = (fk.frames[:, tree.payload_link] @ np.append(tree.payload_com, 1.0))[:, :3]
        pw = np.asarray(payload_kg, float)[:, None] * tree.gravity
        carries = D[:, tree.payload_link] if not strict else tree.descendant[:, tree.payload_link].astype(float)
        F = F + carries[None, :, None] * pw[:, None, :]
        M0 = M0 + carries[None, :, None] * np.cross(pc, pw)[:, None, :]
    ref = fk.link_tip if strict else fk.origins
    return F, M0 - np.cross(ref, F)
