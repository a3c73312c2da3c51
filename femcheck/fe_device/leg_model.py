"""One leg of the device FE model condensed to its platform attachment C_i (vectorized over legs).

Nodes of a leg (all 6-DOF, frame U): B_g guideway tip (slider end of the bar), B_l link end at the ball
centre, C_l link end at the U-joint centre, C_p the platform point C_i. The guideway super-element
(6 x 6, clamped at A_i) acts on B_g, the link super-element (12 x 12) on (B_l, C_l), both rotated from
their part frames with Rot(R) = blockdiag(R, R) (docs/conventions.md §4). The joints (:mod:`.joints`) give

    u_Bl = u_Bg + Rot(R_A) E_act r_act + E_sp r_sp,        u_Cl = u_Cp + Rot(R_B) E_uj r_uj,

so the leg unknowns are q = [u_Bg, r_act, r_sp, r_uj, u_Cp] with u = T q and

    K_q = Tᵀ blockdiag(K_lg, K_link) T + diag(k_springs)     (free joint components: stiffness 0).

Static condensation onto u_Cp gives the leg stiffness at C_i (exact, no load inside the leg):

    K_i = K_bb - K_bi K_ii^-1 K_ib   (6 x 6; rank 6 for rigid joints, rank 1 for released ones,
                                      the FE counterpart of docs/conventions.md §4-5 K_i).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.fe_device.joints import JointLayout
from femcheck.kinematics.frames import rot6

ELEMENTS = ("lg", "act", "sp", "prox", "uj")


def rot12(R: np.ndarray) -> np.ndarray:
    """blockdiag(R, R, R, R): (..., 3, 3) -> (..., 12, 12)."""
    out = np.zeros(R.shape[:-2] + (12, 12))
    for k in range(4):
        out[..., 3 * k:3 * k + 3, 3 * k:3 * k + 3] = R
    return out


@dataclasses.dataclass(frozen=True)
class LegSolution:
    """Condensed legs (n legs, SI). K (n, 6, 6) stiffness at C_i in U; the rest recovers the interior:
    ``Y`` (n, n_inner, 6) with q_inner = -Y u_Cp, ``T`` (n, 18, nq), ``Kel`` (n, 18, 18), ``springs``
    (n, nq) spring stiffnesses on q, ``blocks`` slices of r_act, r_sp, r_uj in q."""

    K: np.ndarray
    Y: np.ndarray
    T: np.ndarray
    Kel: np.ndarray
    springs: np.ndarray
    blocks: dict

    def interior(self, u_C: np.ndarray) -> dict:
        """Leg state for the platform-point twists u_C (n, 6): nodal twists 'B_g', 'B_l', 'C_l' (n, 6)
        and the strain energy (J) of each element type, 'energy' (n, 5) in :data:`ELEMENTS` order."""
        q = np.concatenate([-np.einsum("nij,nj->ni", self.Y, u_C), u_C], axis=1)
        u = np.einsum("nij,nj->ni", self.T, q)
        e = np.zeros((len(q), 5))
        e[:, 0] = 0.5 * np.einsum("ni,nij,nj->n", u[:, :6], self.Kel[:, :6, :6], u[:, :6])
        e[:, 3] = 0.5 * np.einsum("ni,nij,nj->n", u[:, 6:], self.Kel[:, 6:, 6:], u[:, 6:])
        for name, col in (("act", 1), ("sp", 2), ("uj", 4)):
            s = self.blocks[name]
            e[:, col] = 0.5 * np.einsum("ni,ni,ni->n", q[:, s], self.springs[:, s], q[:, s])
        return {"B_g": u[:, :6], "B_l": u[:, 6:12], "C_l": u[:, 12:18], "q": q, "energy": e}


def condense_legs(K_lg_local, K_link_local, R_A, R_B, layout: JointLayout, k_act=None, k_sp=None,
                  k_uj=None) -> LegSolution:
    """Condense n legs onto C_i.

    K_lg_local (n, 6, 6) guideway tip stiffness in frame A; K_link_local (12, 12) or (n, 12, 12) link in
    frame B; R_A, R_B (n, 3, 3) part frames (columns = axes in U); k_act (n,) N/m, k_sp (n,) N/m
    (isotropic Hertz), k_uj (n, 3) N/m in frame B — needed only where ``layout`` has springs.
    """
    K_lg_local = np.asarray(K_lg_local, float)
    n = K_lg_local.shape[0]
    Klink = np.broadcast_to(np.asarray(K_link_local, float), (n, 12, 12))
    Ea, Es, Eu = (layout.selection(c) for c in (layout.act, layout.sp, layout.uj))
    na, ns, nu = Ea.shape[1], Es.shape[1], Eu.shape[1]
    nq = 6 + na + ns + nu + 6
    sa, ss, su = slice(6, 6 + na), slice(6 + na, 6 + na + ns), slice(6 + na + ns, 6 + na + ns + nu)
    RA6, RB6 = rot6(R_A), rot6(R_B)
    T = np.zeros((n, 18, nq))
    T[:, 0:6, 0:6] = np.eye(6)
    T[:, 6:12, 0:6] = np.eye(6)
    T[:, 6:12, sa] = RA6 @ Ea
    T[:, 6:12, ss] = Es
    T[:, 12:18, su] = RB6 @ Eu
    T[:, 12:18, nq - 6:] = np.eye(6)
    Kel = np.zeros((n, 18, 18))
    Kel[:, :6, :6] = RA6 @ K_lg_local @ RA6.swapaxes(-1, -2)
    RB12 = rot12(R_B)
    Kel[:, 6:, 6:] = RB12 @ Klink @ RB12.swapaxes(-1, -2)
    springs = np.zeros((n, nq))
    for comps, spr, sl, k in ((layout.act, layout.act_springs, sa, k_act), (layout.sp, layout.sp_springs, ss, k_sp),
                              (layout.uj, layout.uj_springs, su, k_uj)):
        if not spr:
            continue
        if k is None:
            raise ValueError(f"layout {layout.level}/{layout.joints} needs spring stiffnesses for components {spr}")
        kk = np.broadcast_to(np.asarray(k, float).reshape(n, -1), (n, len(spr)))
        idx = np.arange(sl.start, sl.stop)[[comps.index(c) for c in spr]]
        springs[:, idx] = kk
    Kq = T.swapaxes(-1, -2) @ Kel @ T
    Kq[:, np.arange(nq), np.arange(nq)] += springs
    Kq = 0.5 * (Kq + Kq.swapaxes(-1, -2))
    inner = slice(0, nq - 6)
    Kii, Kib, Kbb = Kq[:, inner, inner], Kq[:, inner, nq - 6:], Kq[:, nq - 6:, nq - 6:]
    Y = np.linalg.solve(Kii, Kib)
    K = Kbb - Kib.swapaxes(-1, -2) @ Y
    K = 0.5 * (K + K.swapaxes(-1, -2))
    return LegSolution(K=K, Y=Y, T=T, Kel=Kel, springs=springs, blocks={"act": sa, "sp": ss, "uj": su})
