"""Self-weight elastic equilibrium of a kinematic tree (issue 23 item 2).

Springs (all lumped, linear unless stated):

* torsion of each independent joint, compliance c_t (rad/(N m)): dq = c_t tau with tau = E^T (M_j . z_j) the
  gravity torque of the rows it drives (E the coupling matrix: a passive coupled row passes its torque on by
  virtual work, q_rows = E q_ind);
* backlash (gear clearance) b (rad): dq = b tanh(tau / tau_s): the joint settles on the flank the gravity torque
  pushes it to, and changes side when the torque changes sign (tau_s the take-up width);
* two tilt springs per row (seed 002's extended VJM), compliances c_x, c_y about the joint frame's x and y:
  phi = (c_x M.x, c_y M.y);
* bending of the row's link (root = joint origin, tip = row-frame origin), compliance c_b = 1/(EI): the tip load
  of everything below (force F and moment M about the tip, transverse parts) moves the tip by
  u = c_b (L^3/3 F_perp + L^2/2 M_perp x e) and turns it by th = c_b (L^2/2 e x F_perp + L M_perp)
  (Euler-Bernoulli cantilever, e.g. Roark's Formulas Table 8.1 cases 1a and 3a); the link's own weight is left out.

The equilibrium is taken by ``passes`` fixed-point passes: pass 1 loads the springs with the weights at the
rigid configuration; every further pass reloads them at the deflected configuration of the pass before.
Everything is vectorized over poses.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.robot.tree import Geometry, RobotTree, TreePoses, forward, gravity_wrenches


@dataclasses.dataclass(frozen=True)
class ElasticParams:
    """``torsion`` (n_ind,) rad/(N m); ``tilt`` (n, 2) rad/(N m); ``backlash`` (n_ind,) rad; ``bending`` (n,)
    1/(N m^2); ``mass_scale`` (-): factor on every link mass (not the payload)."""

    torsion: np.ndarray
    tilt: np.ndarray
    backlash: np.ndarray
    bending: np.ndarray
    mass_scale: float = 1.0

    @classmethod
    def nominal(cls, tree: RobotTree) -> "ElasticParams":
        return cls(tree.compliance_torsion.copy(), tree.compliance_tilt.copy(), tree.backlash.copy(),
                   tree.compliance_bending.copy(), 1.0)

    @property
    def is_rigid(self) -> bool:
        return not (np.any(self.torsion) or np.any(self.tilt) or np.any(self.backlash) or np.any(self.bending))

    # flat vector of the cause space: torsion (n_ind), tilt increment (n, both axes), backlash (n_ind), bending (n), mass scale
    def flat(self) -> np.ndarray:
        return np.concatenate([self.torsion, self.tilt.mean(axis=1), self.backlash, self.bending, [self.mass_scale]])

    def shifted(self, tree: RobotTree, delta: np.ndarray) -> "ElasticParams":
        """These parameters plus a flat increment ``delta`` (the layout of :func:`flat_layout`)."""
        ni, n = tree.n_joints, tree.n_rows
        s = np.cumsum([0, ni, n, ni, n, 1])
        return ElasticParams(self.torsion + delta[s[0]:s[1]], self.tilt + delta[s[1]:s[2], None],
                             self.backlash + delta[s[2]:s[3]], self.bending + delta[s[3]:s[4]],
                             float(self.mass_scale + delta[s[4]]))


def flat_layout(tree: RobotTree) -> dict[str, slice]:
    ni, n = tree.n_joints, tree.n_rows
    s = np.cumsum([0, ni, n, ni, n, 1])
    return {"torsion": slice(s[0], s[1]), "tilt": slice(s[1], s[2]), "backlash": slice(s[2], s[3]),
            "bending": slice(s[3], s[4]), "mass_scale": slice(s[4], s[5])}


def joint_torques(tree: RobotTree, fk: TreePoses, M: np.ndarray) -> np.ndarray:
    """(m, n_ind) gravity torque on each independent joint (coupled rows pass theirs on by E^T)."""
    tau_rows = np.einsum("mnk,mnk->mn", M, fk.joint_frames[..., :3, 2])
    return tau_rows @ tree.coupling


def equilibrium(tree: RobotTree, q_ind: np.ndarray, geometry: Geometry | None, params: ElasticParams,
                passes: int = 2, payload_kg: np.ndarray | None = None, backlash_width: np.ndarray | None = None) -> TreePoses:
    """Deflected poses under self-weight: (m, n_ind) independent joint angles rad -> :class:`TreePoses`.

    ``backlash_width`` (n_ind,) N m: tau_s of the tanh take-up (needed when any backlash is non-zero).
    """
    q_rows = q_ind @ tree.coupling.T
    fk = forward(tree, q_rows, geometry)
    if params.is_rigid:
        return fk
    has_tilt, has_bend = bool(np.any(params.tilt)), bool(np.any(params.bending))
    for _ in range(passes):
        F, M = gravity_wrenches(tree, fk, payload_kg, params.mass_scale)
        tau = joint_torques(tree, fk, M)
        dq = params.torsion * tau
        if np.any(params.backlash):
            dq = dq + params.backlash * np.tanh(tau / backlash_width)
        tilt = None
        if has_tilt:
            Mx = np.einsum("mnk,mnk->mn", M, fk.joint_frames[..., :3, 0])
            My = np.einsum("mnk,mnk->mn", M, fk.joint_frames[..., :3, 1])
            tilt = np.stack([params.tilt[:, 0] * Mx, params.tilt[:, 1] * My], axis=-1)
        bend = None
        if has_bend:
            Ft, Mt = gravity_wrenches(tree, fk, payload_kg, params.mass_scale, strict=True)
            bend = link_bending(tree, fk, Ft, Mt, params.bending, params.mass_scale)
        fk = forward(tree, q_rows + dq @ tree.coupling.T, geometry, tilt, bend)
    return fk


def link_bending(tree: RobotTree, fk: TreePoses, F: np.ndarray, M: np.ndarray, c: np.ndarray,
                 mass_scale: float = 1.0) -> np.ndarray:
    """(m, n, 6) tip translation and rotation of each row's link as a cantilever (module docstring).

    ``F``, ``M`` (m, n, 3): the load of everything below the link, about its tip. The link's own weight W acts
    at its centre of mass projected on the link, distance s from the root: u = c W_perp s^2 (3L - s)/6,
    th = c s^2/2 e x W_perp (Roark Table 8.1 case 1a at an intermediate point; its off-axis moment is left out).
    """
    root, tip = fk.origins, fk.link_tip
    L_vec = tip - root
    L = np.linalg.norm(L_vec, axis=-1)
    e = L_vec / np.where(L > 1e-12, L, 1.0)[..., None]
    perp = lambda v: v - np.einsum("mnk,mnk->mn", v, e)[..., None] * e
    Fp, Mp = perp(F), perp(M)
    Ln = L[..., None]
    cL = (c * np.ones_like(L))[..., None]
    u = cL * (Ln ** 3 / 3 * Fp + Ln ** 2 / 2 * np.cross(Mp, e))
    th = cL * (Ln ** 2 / 2 * np.cross(e, Fp) + Ln * Mp)
    com = np.einsum("mnij,nj->mni", fk.frames, np.append(tree.com, np.ones((tree.n_rows, 1)), axis=1))[..., :3]
    s = np.clip(np.einsum("mnk,mnk->mn", com - root, e), 0.0, L)[..., None]
    W = perp(np.broadcast_to(tree.mass * mass_scale, L.shape)[..., None] * tree.gravity)
    u = u + cL * W * s ** 2 * (3 * Ln - s) / 6
    th = th + cL * s ** 2 / 2 * np.cross(e, W)
    return np.concatenate([u, th], axis=-1)
