"""Leg geometry of the HISS haptic device, an R-CUBE decoupled translational parallel manipulator (seed 001 sec. 2).

The seed gives the link lengths (l1 = 122.3 mm, l2 = 80 mm, l3 = 129.3 mm), the decoupled forward
kinematics ``r_i = S + l1 sin(phi_i1)`` with ``S = l1 + d`` (eq. 1), the +-30 deg active range and a knee
angle that stays negative, but no drawing with dimensions. femcheck ASSUMES the following layout, which
reproduces eq. 1 exactly (the case file repeats it):

* Leg i (i = 0, 1, 2) moves platform coordinate i. With (e_i, e_j, e_k) the base axes in cyclic order
  (leg 0: x, y, z), its active revolute axis is parallel to e_k through ``A = S e_i + (S + l1) e_j + (S - h) e_k``.
* The crank (link 1, length l1) ends at ``B = A + l1 (sin phi e_i - cos phi e_j)``, so ``B_i = S + l1 sin phi``.
* Three passive revolute joints with axes parallel to e_i sit at B, at the knee C and at the platform
  point P (the intersection of the platform axes, the MP frame origin). Links 2 (B->C, l2) and 3 (C->P, l3)
  move in the plane ``x_i = B_i``, hence ``P_i = B_i``: eq. 1. The knee is solved in that plane, with a
  negative knee angle (seed 001 sec. 2.1).
* h (``knee_plane_offset_m``) places the crank below the platform; 130 mm keeps every corner of the
  +-30 deg cube reachable (knee angle between about -21 and -152 deg).
* Eq. 1 does not fix where the crank axis sits along e_j: ``A = S e_i + (S + c) e_j + (S - h) e_k`` keeps it for
  any c (``crank_axis_offset_m``, default c = l1, the layout above). The layout search of docs/vjm.md varies
  c and h.

Link frames (where each link's 6x6 stiffness of the seed's Appendix acts): origin at the link's distal end,
x along the link from its proximal to its distal joint, z along the joint axis at its proximal end (the
active axis for the crank, e_i for links 2 and 3), y = z x x. This matches the Appendix matrices, which
have the cantilever couplings ``K[1,5] = -6EI/L^2`` and ``K[2,4] = +6EI/L^2`` of a beam clamped at its
proximal end (L = 2 K[1,5]/K[1,1] = 122.4 mm and 129.6 mm for links 1 and 3, i.e. l1 and l3).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from femcheck.errors import UnreachablePoseError


@dataclass(frozen=True)
class RCubeGeometry:
    """Dimensions in m: crank ``l1``, coupler ``l2``, distal link ``l3``, platform cube edge ``d``,
    ``knee_plane_offset_m`` h; ``active_limit_rad`` on |phi|; ``crank_axis_offset_m`` c (None: c = l1)."""

    l1: float
    l2: float
    l3: float
    d: float
    knee_plane_offset_m: float
    active_limit_rad: float = np.deg2rad(30.0)
    crank_axis_offset_m: float | None = None

    @property
    def c(self) -> float:
        """Crank axis offset along e_j from S, m (module doc)."""
        return self.l1 if self.crank_axis_offset_m is None else self.crank_axis_offset_m

    @property
    def S(self) -> float:
        """S = l1 + d, m (seed 001 eq. 1)."""
        return self.l1 + self.d


@dataclass(frozen=True)
class LegPoses:
    """Joint points and frames of the 3 legs at m platform positions (leading axes (3, m)).

    ``A``, ``B``, ``C`` (3, m, 3) m; ``active_axis`` (3, m, 3); ``passive_axis`` (3, m, 3) (e_i);
    ``knee_rad`` (3, m); ``link_origins`` (3, m, 3 links, 3); ``link_axes`` (3, m, 3 links, 3, 3).
    """

    phi: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    P: np.ndarray
    active_axis: np.ndarray
    passive_axis: np.ndarray
    knee_rad: np.ndarray
    link_origins: np.ndarray
    link_axes: np.ndarray


def forward_position(geom: RCubeGeometry, phi) -> np.ndarray:
    """Platform point P (m, 3) from active angles phi (m, 3) rad: r_i = S + l1 sin phi_i (seed 001 eq. 1)."""
    phi = np.atleast_2d(np.asarray(phi, dtype=float))
    return geom.S + geom.l1 * np.sin(phi)


def inverse_position(geom: RCubeGeometry, P, label: str = "P") -> np.ndarray:
    """Active angles (m, 3) rad for platform points P (m, 3) m; raises UnreachablePoseError outside +-limit."""
    P = np.atleast_2d(np.asarray(P, dtype=float))
    s = (P - geom.S) / geom.l1
    bad = np.abs(s) > np.sin(geom.active_limit_rad) + 1e-12
    if bad.any():
        row, leg = np.argwhere(bad)[0]
        raise UnreachablePoseError(label, int(leg), f"|r_{leg} - S| = {abs(P[row, leg] - geom.S) * 1e3:.2f} mm exceeds "
                                   f"l1 sin({np.rad2deg(geom.active_limit_rad):.0f} deg) = {geom.l1 * np.sin(geom.active_limit_rad) * 1e3:.2f} mm")
    return np.arcsin(s)


def _frame(x: np.ndarray, z_hint: np.ndarray) -> np.ndarray:
    """Rotation (..., 3, 3) with columns x, y = z x x, z = z_hint made orthogonal to x."""
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    z = z_hint - np.sum(z_hint * x, axis=-1, keepdims=True) * x
    z = z / np.linalg.norm(z, axis=-1, keepdims=True)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=-1)


def leg_poses(geom: RCubeGeometry, P, label: str = "P") -> LegPoses:
    """Positions of every joint of the three legs for platform points P (m, 3) m (layout in the module doc)."""
    P = np.atleast_2d(np.asarray(P, dtype=float))
    m = P.shape[0]
    phi = inverse_position(geom, P, label)
    E = np.eye(3)
    S, l1, l2, l3, h = geom.S, geom.l1, geom.l2, geom.l3, geom.knee_plane_offset_m
    out = {k: np.empty((3, m, 3)) for k in ("A", "B", "C", "a", "u")}
    knee = np.empty((3, m))
    for i in range(3):                                   # three legs; every line vectorized over m poses
        ei, ej, ek = E[i], E[(i + 1) % 3], E[(i + 2) % 3]
        A = S * ei + (S + geom.c) * ej + (S - h) * ek
        ph = phi[:, i:i + 1]
        B = A + l1 * (np.sin(ph) * ei - np.cos(ph) * ej)
        # knee in the plane normal to e_i: 2R chain B -> C -> P
        dj, dk = (P - B) @ ej, (P - B) @ ek
        rho2 = dj**2 + dk**2
        cq = (rho2 - l2**2 - l3**2) / (2 * l2 * l3)
        if np.any(np.abs(cq) > 1):
            r = int(np.argmax(np.abs(cq) > 1))
            raise UnreachablePoseError(label, i, f"coupler-distal distance {np.sqrt(rho2[r]) * 1e3:.1f} mm outside "
                                       f"[{abs(l2 - l3) * 1e3:.1f}, {(l2 + l3) * 1e3:.1f}] mm")
        q3 = -np.arccos(cq)                                # negative knee configuration
        psi = np.arctan2(dk, dj) - np.arctan2(l3 * np.sin(q3), l2 + l3 * np.cos(q3))
        C = B + l2 * (np.cos(psi)[:, None] * ej + np.sin(psi)[:, None] * ek)
        out["A"][i], out["B"][i], out["C"][i] = A, B, C
        out["a"][i], out["u"][i] = ek, ei
        knee[i] = q3
    A, B, C = out["A"], out["B"], out["C"]
    Pl = np.broadcast_to(P, (3, m, 3))
    origins = np.stack([B, C, Pl], axis=2)                 # (3, m, 3 links, 3)
    axes = np.stack([_frame(B - A, out["a"]), _frame(C - B, out["u"]), _frame(Pl - C, out["u"])], axis=2)
    return LegPoses(phi=phi, A=A, B=B, C=C, P=P, active_axis=out["a"], passive_axis=out["u"], knee_rad=knee,
                    link_origins=origins, link_axes=axes)


def leg_jacobians(legs: LegPoses) -> tuple[np.ndarray, np.ndarray]:
    """Jacobians of every leg at the platform point P (seed 001 eq. 2).

    Returns ``J_theta`` (3 legs, m, 6, 18): the 6-DOF virtual springs of links 1-3 (each ``[d; theta]`` in its
    link frame) and ``J_phi`` (3, m, 6, 3): the passive revolute joints at B, C and P (axes e_i).
    The active joint is locked (rigid) and has no column.
    """
    from femcheck.vjm.parallel_vjm import link_jacobian, passive_jacobian

    L, m = legs.B.shape[:2]
    P = np.broadcast_to(legs.P, (L, m, 3)).reshape(-1, 3)
    Jt = [link_jacobian(P, legs.link_origins[:, :, j].reshape(-1, 3), legs.link_axes[:, :, j].reshape(-1, 3, 3))
          for j in range(3)]
    J_theta = np.concatenate(Jt, axis=-1).reshape(L, m, 6, 18)
    axes = np.repeat(legs.passive_axis[:, :, None, :], 3, axis=2).reshape(-1, 3, 3)
    origins = np.stack([legs.B, legs.C, np.broadcast_to(legs.P, legs.B.shape)], axis=2).reshape(-1, 3, 3)
    J_phi = passive_jacobian(axes, origins, P).reshape(L, m, 6, 3)
    return J_theta, J_phi


def rcube_stiffness(geom: RCubeGeometry, K_theta: np.ndarray, P, label: str = "P") -> tuple[np.ndarray, np.ndarray]:
    """Leg stiffnesses (3, m, 6, 6) and platform stiffness (m, 6, 6) at platform points P (m, 3) m, for the
    (18, 18) virtual-joint stiffness ``K_theta`` of one leg (seed 001 eqs. 2-6, legs summed)."""
    from femcheck.vjm.parallel_vjm import parallel_stiffness

    J_theta, J_phi = leg_jacobians(leg_poses(geom, P, label))
    return parallel_stiffness(J_theta, K_theta, J_phi)
