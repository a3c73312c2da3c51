"""Legs joined by the rigid platform: assembly of the condensed legs, and the whole-device check solve.

The platform is rigid and the legs touch each other only through it, so with the leg stiffness K_i at
C_i (:mod:`.leg_model`) the TCP stiffness is exactly (docs/conventions.md §4)

    K_T = Σ_i G_iᵀ K_i G_i,   G_i = Jf(C_i - T)ᵀ,   t_T = K_T⁻¹ W_T,   u_C,i = G_i t_T.

:func:`whole_device_solve` builds the same device as ONE sparse FE model (all guideway and link meshes,
reference nodes, joint couplings, the platform as a rigid coupling of the six C_i to the TCP node) and
solves it directly; it exists to show that the substructured answer is the same (tests, docs/verify.md).
"""
from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np
import scipy.sparse as sp

from femcheck.kinematics.frames import wrench_shift

log = logging.getLogger(__name__)


def platform_matrices(C, tcp) -> np.ndarray:
    """G_i = Jf(C_i - T)ᵀ (..., 6, 6, 6): TCP twist -> twist of platform point C_i. C (..., 6, 3), tcp (..., 3) m."""
    C = np.asarray(C, float)
    r = C - np.asarray(tcp, float)[..., None, :]
    return wrench_shift(r).swapaxes(-1, -2)


def platform_stiffness(K_legs, G) -> np.ndarray:
    """K_T = Σ_i G_iᵀ K_i G_i: K_legs (..., 6, 6, 6), G (..., 6, 6, 6) -> (..., 6, 6)."""
    return np.einsum("...iba,...ibc,...icd->...ad", G, K_legs, G)


def solve_platform(K_legs, G, wrench):
    """TCP twist t_T (..., 6) and platform-point twists u_C (..., 6, 6) under ``wrench`` (..., 6) N, N m."""
    KT = platform_stiffness(K_legs, G)
    t = np.linalg.solve(KT, np.asarray(wrench, float)[..., None])[..., 0]
    return t, np.einsum("...iab,...b->...ia", G, t)


@dataclasses.dataclass(frozen=True)
class WholeDeviceResult:
    """One direct FE solve of the whole device: ``twist`` (6,) TCP twist m, rad; ``dofs`` unknowns after
    constraint elimination; ``seconds`` wall time (assembly + solve)."""

    twist: np.ndarray
    dofs: int
    seconds: float


def _rotate_triplets(K, R):
    """Qᵀ-free rotation of a triplet-ordered matrix to U: K_U = Q K Qᵀ, Q = blockdiag(R, ..., R)."""
    n = K.shape[0] // 3
    Q = sp.kron(sp.identity(n, format="csr"), sp.csr_matrix(R), format="csr")
    return sp.csr_matrix(Q @ K @ Q.T)


def whole_device_solve(case, point: str, wrench, joints: str = "rigid", guideway_size_m=None,
                       link_kind: str = "beam", link_size_m=None) -> WholeDeviceResult:
    """Direct solve of the whole simplified-level device at test point ``point`` (e.g. 'P0').

    Solid guideways (P2, mesh size ``guideway_size_m``), links as solids or beams (``link_kind``),
    joints as couplings of the ``joints`` idealization (:mod:`.joints`), platform rigid. ``wrench`` (6,)
    at the TCP (N, N m).
    """
    from femcheck.kinematics.frames import guideway_frames, link_frames
    from femcheck.fe import constraints as cs
    from femcheck.fe.beam import BeamSection, assemble_beam_stiffness
    from femcheck.fe.elasticity import assemble_stiffness, dof_triplets, vector_basis
    from femcheck.fe.linear_solver import factorize
    from femcheck.kinematics.points import point_set
    from geometry import guideway, proximal_link

    t0 = time.perf_counter()
    legs = point_set(case, [point]).legs
    A, B, C, u, s = legs.A, legs.B[0], legs.C[0], legs.u[0], legs.slider[0]
    RA, RB = guideway_frames(case), link_frames(u)
    tcp = legs.tcp[0]
    blocks, offset = [], 0
    parts = []  # per leg: dict of region -> (points U, dof triplets) and beam node dofs
    lg_mat, pl = case.guideway.material, case.proximal_link
    link_pm = proximal_link.build(case, link_size_m) if link_kind == "solid" else None
    if link_pm is not None:
        lbasis = vector_basis(link_pm.to_skfem(), 2)
        Klink = assemble_stiffness(lbasis, pl.material.E_Pa, pl.material.nu)
    for i in range(6):
        leg = {}
        pm = guideway.build(case, guideway_size_m, length_m=float(s[i]))
        basis = vector_basis(pm.to_skfem(), 2)
        blocks.append(_rotate_triplets(assemble_stiffness(basis, lg_mat.E_Pa, lg_mat.nu), RA[i]))
        for reg in ("lg_clamp", "lg_slider"):
            pts, trip = dof_triplets(basis, basis.get_dofs(reg).all())
            leg[reg] = (pts @ RA[i].T + A[i], trip + offset)
        offset += basis.N
        if link_pm is not None:
            blocks.append(_rotate_triplets(Klink, RB[i]))
            for reg in ("prox_end_B", "prox_end_C"):
                pts, trip = dof_triplets(lbasis, lbasis.get_dofs(reg).all())
                leg[reg] = (pts @ RB[i].T + B[i], trip + offset)
            offset += lbasis.N
        else:
            sec = BeamSection.tube(pl.outer_diameter_m, pl.inner_diameter_m, pl.material.nu)
            blocks.append(assemble_beam_stiffness(np.stack([B[i], C[i]]), [[0, 1]], pl.material.E_Pa, pl.material.G_Pa,
                                                  sec, orientation=RB[i][:, 0], shear=case.model.beam_shear))
            leg["beam"] = offset + np.arange(12).reshape(2, 6)
            offset += 12
        parts.append(leg)
    n_ref = 6 * (4 if link_pm is not None else 2) + 1
    ndof, ref = cs.append_reference_nodes(offset, n_ref)
    K = cs.pad(sp.block_diag(blocks, format="csr"), ndof)
    tcp_dofs = ref[-1]
    sets = []
    Cp_all = []
    for i, leg in enumerate(parts):
        Bg, Cp = ref[4 * i] if link_pm is not None else ref[2 * i], ref[4 * i + 3] if link_pm is not None else ref[2 * i + 1]
        Cp_all.append(Cp)
        sets.append(cs.clamp(ndof, leg["lg_clamp"][1].ravel()))
        sets.append(cs.rigid_coupling(ndof, Bg, B[i], *leg["lg_slider"]))
        if link_pm is not None:
            Bl, Cl = ref[4 * i + 1], ref[4 * i + 2]
            sets.append(cs.rigid_coupling(ndof, Bl, B[i], *leg["prox_end_B"]))
            sets.append(cs.rigid_coupling(ndof, Cl, C[i], *leg["prox_end_C"]))
        else:
            Bl, Cl = leg["beam"]
        # spherical joint at B: ties translations; rotations too for the rigid idealization
        sets.append(cs.rigid_coupling(ndof, Bg, B[i], B[i][None], Bl[None, :3],
                                      rot_dofs=Bl[None, 3:] if joints == "rigid" else None))
        if joints == "rigid":
            sets.append(cs.rigid_coupling(ndof, Cp, C[i], C[i][None], Cl[None, :3], rot_dofs=Cl[None, 3:]))
        else:  # U joint: translations tied, rotation about u_i tied, rotations about a1, a2 free
            sets.append(cs.rigid_coupling(ndof, Cp, C[i], C[i][None], Cl[None, :3]))
            kk = int(np.argmax(np.abs(u[i])))
            D = sp.lil_matrix((1, ndof))
            for j in range(3):
                D[0, Cp[3 + j]] += u[i][j] / u[i][kk]
                if j != kk:
                    D[0, Cl[3 + j]] -= u[i][j] / u[i][kk]
            sets.append(cs._from_relations(ndof, np.array([Cl[3 + kk]]), D.tocsr(), np.zeros(1)))
    Cp_all = np.array(Cp_all)
    sets.append(cs.rigid_coupling(ndof, tcp_dofs, tcp, C, Cp_all[:, :3], rot_dofs=Cp_all[:, 3:]))
    con = cs.combine(*sets)
    f = cs.nodal_wrench(ndof, tcp_dofs, wrench)
    Kr = con.reduce_matrix(K)
    q = factorize(Kr, symmetric=True).solve(con.reduce_vector(f))
    uu = con.expand(q)
    return WholeDeviceResult(twist=uu[tcp_dofs].copy(), dofs=con.nfree, seconds=time.perf_counter() - t0)
