"""Self-weight elastic equilibrium of a kinematic tree.

Springs (all lumped, linear unless stated):

* torsion of each independent joint, compliance c_t (rad/(N m)): dq = c_t tau with tau = E^T (M_j . z_j) the
  gravity torque of the rows it drives (E the coupling matrix: a passive coupled row passes its torque on by
  virtual work, q_rows = E q_ind);
* torsion of a coupled row's own spring (the compliance of its transmission: a parallelogram's rods, a
  mimic belt), c_c: the row turns by c_c tau_row on top of what its coupling gives, in series; the row's torque
  tau_row still reaches the driving joints through E^T (the series spring carries it, it does not absorb it):
  dq_rows = E (c_t tau) + c_c tau_rows;
* on a prismatic row the joint coordinate is the slide: its drive compliance is axial, c_a (m/N), loaded by the
  force along the slide F_j . z_j (same coupling and series rules);
* backlash (gear clearance) b (rad): dq = b tanh(tau / tau_s): the joint settles on the flank the gravity torque
  pushes it to, and changes side when the torque changes sign (tau_s the take-up width);
* two tilt springs per row (seed 002's extended VJM), compliances c_x, c_y about the joint frame's x and y:
  phi = (c_x M.x, c_y M.y);
* guide play of a prismatic row's moving stage: a guide (bushing, linear bearing) of diametral clearance delta
  engaged over the overlap L(q) = L0 - q lets the stage tilt by up to delta / L(q) -- the angle a shaft takes
  across its clearance in a bore of length L, plain geometry of two contact lines at the bore's ends (Slocum,
  Precision Machine Design, 1992, sliding-contact bearings; the same play law sets a linear-guide carriage's
  moment play). The stage settles on the side the moment M_perp (x, y parts at the carriage) pushes it to:
  phi = delta / L(q) M_perp / sqrt(|M_perp|^2 + M_s^2), M_s a take-up width; the pivot is the carriage origin;
  the play grows as the overlap shrinks, which no linear spring does;
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
    """``torsion`` (n,) rad/(N m) per row (independent rows: the drive; coupled rows: their own series spring);
    prismatic rows: m/N axial; ``tilt`` (n, 2) rad/(N m); ``backlash`` (n_ind,) rad; ``bending`` (n,)
    1/(N m^2); ``guide`` (n,) m diametral guide clearance of prismatic rows; ``mass_scale`` (-): factor on every
    link mass (not the payload)."""

    torsion: np.ndarray
    tilt: np.ndarray
    backlash: np.ndarray
    bending: np.ndarray
    guide: np.ndarray
    mass_scale: float = 1.0

    @classmethod
    def nominal(cls, tree: RobotTree) -> "ElasticParams":
        return cls(tree.compliance_torsion.copy(), tree.compliance_tilt.copy(), tree.backlash.copy(),
                   tree.compliance_bending.copy(), tree.guide_clearance.copy(), 1.0)

    @classmethod
    def rigid(cls, tree: RobotTree) -> "ElasticParams":
        return cls(np.zeros(tree.n_rows), np.zeros((tree.n_rows, 2)), np.zeros(tree.n_joints), np.zeros(tree.n_rows),
                   np.zeros(tree.n_rows), 1.0)

    @property
    def is_rigid(self) -> bool:
        return not (np.any(self.torsion) or np.any(self.tilt) or np.any(self.backlash) or np.any(self.bending)
                    or np.any(self.guide))

    # flat vector of the cause space: torsion (n), tilt increment (n, both axes), backlash (n_ind), bending (n),
    # guide clearance (n), mass scale
    def flat(self) -> np.ndarray:
        return np.concatenate([self.torsion, self.tilt.mean(axis=1), self.backlash, self.bending, self.guide,
                               [self.mass_scale]])

    def shifted(self, tree: RobotTree, delta: np.ndarray) -> "ElasticParams":
        """These parameters plus a flat increment ``delta`` (the layout of :func:`flat_layout`)."""
        lay = flat_layout(tree)
        return ElasticParams(self.torsion + delta[lay["torsion"]], self.tilt + delta[lay["tilt"], None],
                             self.backlash + delta[lay["backlash"]], self.bending + delta[lay["bending"]],
                             self.guide + delta[lay["guide"]], float(self.mass_scale + delta[lay["mass_scale"].start]))


def flat_layout(tree: RobotTree) -> dict[str, slice]:
    ni, n = tree.n_joints, tree.n_rows
    s = np.cumsum([0, n, n, ni, n, n, 1])
    return {"torsion": slice(s[0], s[1]), "tilt": slice(s[1], s[2]), "backlash": slice(s[2], s[3]),
            "bending": slice(s[3], s[4]), "guide": slice(s[4], s[5]), "mass_scale": slice(s[5], s[6])}


def row_torques(tree: RobotTree, fk: TreePoses, M: np.ndarray, F: np.ndarray | None = None) -> np.ndarray:
    """(m, n) generalized gravity force of each row along its own joint coordinate: the torque M . z (N m) about
    a revolute row's axis, the force F . z (N) along a prismatic row's slide (``F`` needed when the tree has one)."""
    z = fk.joint_frames[..., :3, 2]
    tau = np.einsum("mnk,mnk->mn", M, z)
    if tree.prismatic.any():
        if F is None:
            raise ValueError("row_torques: a tree with prismatic rows needs the forces F")
        tau = np.where(tree.prismatic, np.einsum("mnk,mnk->mn", F, z), tau)
    return tau


def joint_torques(tree: RobotTree, fk: TreePoses, M: np.ndarray, F: np.ndarray | None = None) -> np.ndarray:
    """(m, n_ind) generalized gravity force on each independent joint (coupled rows pass theirs on by E^T)."""
    return row_torques(tree, fk, M, F) @ tree.coupling


def stage_moments(fk: TreePoses, M: np.ndarray) -> np.ndarray:
    """(m, n, 2) moment about each row's joint-frame x and y (tilt springs, guide play)."""
    return np.einsum("mnk,mnka->mna", M, fk.joint_frames[..., :3, :2])


def guide_widths(tree: RobotTree, fk: TreePoses, M: np.ndarray) -> np.ndarray:
    """(n,) N m take-up width M_s of the guide play: 5 % of each row's median |M_perp| over the poses (1e-6 floor)."""
    return np.maximum(0.05 * np.median(np.linalg.norm(stage_moments(fk, M), axis=-1), axis=0), 1e-6)


def guide_overlap(tree: RobotTree, q_rows: np.ndarray) -> np.ndarray:
    """(m, n) m engaged guide length L(q) = L0 - q of each prismatic row with a stated overlap (nan elsewhere)."""
    return np.where(tree.prismatic & np.isfinite(tree.guide_overlap), tree.guide_overlap - q_rows, np.nan)


def equilibrium(tree: RobotTree, q_ind: np.ndarray, geometry: Geometry | None, params: ElasticParams,
                passes: int = 2, payload_kg: np.ndarray | None = None, backlash_width: np.ndarray | None = None,
                guide_width: np.ndarray | None = None, start: tuple | None = None) -> TreePoses:
    """Deflected poses under self-weight: (m, n_ind) independent joint coordinates (rad; m on prismatic joints)
    -> :class:`TreePoses`.

    ``backlash_width`` (n_ind,) N m: tau_s of the tanh take-up (needed when any backlash is non-zero);
    ``guide_width`` (n,) N m: M_s of the guide play (needed when any guide clearance is non-zero).
    ``start``: (poses, F, M, mass_scale) -- the undeflected :class:`TreePoses` of these joint coordinates and
    geometry and the weights' wrenches there at that mass scale -- to skip recomputing them (many elastic
    parameter sets at one point: a forward-difference Jacobian).
    """
    q_rows = q_ind @ tree.coupling.T
    fk = forward(tree, q_rows, geometry) if start is None else start[0]
    if params.is_rigid:
        return fk
    has_tilt, has_bend = bool(np.any(params.tilt)), bool(np.any(params.bending))
    guided = np.flatnonzero(params.guide)
    if len(guided):
        overlap = guide_overlap(tree, q_rows)[:, guided]
        if not np.all(overlap > 0):
            raise ValueError("equilibrium: guide clearance on rows without a positive overlap L(q) = L0 - q")
        play = params.guide[guided] / overlap                  # (m, k) rad: the most the stage can tilt
    own = np.where(tree.coupled, params.torsion, 0.0)            # coupled rows' own series springs
    has_own = bool(np.any(own))
    for k in range(passes):
        if k == 0 and start is not None and start[3] == params.mass_scale:
            F, M = start[1], start[2]
        else:
            F, M = gravity_wrenches(tree, fk, payload_kg, params.mass_scale)
        tau_rows = row_torques(tree, fk, M, F)
        tau = tau_rows @ tree.coupling
        dq = params.torsion[tree.independent] * tau
        if np.any(params.backlash):
            dq = dq + params.backlash * np.tanh(tau / backlash_width)
        dq_rows = dq @ tree.coupling.T
        if has_own:
            dq_rows = dq_rows + own * tau_rows
        tilt = None
        if has_tilt or len(guided):
            Mxy = stage_moments(fk, M)
            tilt = params.tilt * Mxy
            if len(guided):
                Mg = Mxy[:, guided]
                norm = np.sqrt((Mg ** 2).sum(axis=-1) + guide_width[guided] ** 2)
                tilt[:, guided] += play[..., None] * Mg / norm[..., None]
        bend = None
        if has_bend:
            Ft, Mt = gravity_wrenches(tree, fk, payload_kg, params.mass_scale, strict=True)
            bend = link_bending(tree, fk, Ft, Mt, params.bending, params.mass_scale)
        fk = forward(tree, q_rows + dq_rows, geometry, tilt, bend)
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
