"""Pretensioned cable (truss) element: two nodes, three translations each, axial plus geometric stiffness.

A straight strand from node 1 to node 2 (length L, unit vector e = (x2 − x1) / L), axial rigidity EA (N) and
tension T (N) in the reference state. Linearized about that state, the element stiffness (6 × 6, N/m) on
(u1, u2) is

    K = [[k, −k], [−k, k]],   k = EA / L · e eᵀ  +  T / L · (I − e eᵀ)

(the material term along the strand plus the geometric (initial-stress) stiffness of the pretension across
it: the linearized truss with initial stress of nonlinear FE texts, e.g. Bathe, *Finite Element Procedures*,
ch. 6). A tension-only cable
is linear as long as T + ΔT stays > 0; :func:`cable_tensions` gives T + ΔT of a displacement so a caller can
check that no strand goes slack.

Properties (tested in ``tests/test_fe_cable.py``): K is symmetric and positive semi-definite; a rigid
translation gives zero force; the end forces of any displacement sum to zero; with T = 0 a small rigid
rotation gives zero force. With T > 0 the linearized rotation u2 − u1 = θ × (x2 − x1) costs uᵀ K u = T L θ²:
it stretches the chord by L θ² / 2 at second order, and the rotation along the exact arc (which is free) differs
from it by exactly that second-order motion, so this is the geometric stiffness doing its job, not a defect.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from femcheck.fe.beam import element_axes


def strand_geometry(nodes, elements):
    """(unit vectors (ne, 3), lengths (ne,) m) of the strands ``elements`` (ne, 2) between ``nodes`` (n, 3) m."""
    return element_axes(nodes, elements, "cable strand")


def cable_stiffness(e, L, EA, tension) -> np.ndarray:
    """Element stiffness (ne, 6, 6) N/m on (u1, u2) of strands with unit vectors ``e`` (ne, 3), lengths ``L``
    (ne,) m, axial rigidity ``EA`` N and reference tension ``tension`` N (scalars or (ne,))."""
    e = np.atleast_2d(np.asarray(e, dtype=float))
    L = np.atleast_1d(np.asarray(L, dtype=float))
    EA = np.broadcast_to(np.asarray(EA, dtype=float), L.shape)
    T = np.broadcast_to(np.asarray(tension, dtype=float), L.shape)
    ee = np.einsum("ei,ej->eij", e, e)
    k = (EA / L)[:, None, None] * ee + (T / L)[:, None, None] * (np.eye(3) - ee)
    K = np.zeros((len(L), 6, 6))
    K[:, :3, :3] = k
    K[:, 3:, 3:] = k
    K[:, :3, 3:] = -k
    K[:, 3:, :3] = -k
    return K


def assemble_cable_stiffness(nodes, elements, EA, tension, ndof: int | None = None,
                             dof_offset: int = 0) -> sp.csr_matrix:
    """Global stiffness (ndof × ndof, csr) of cable strands; node k's translations at ``dof_offset + 3k + (0..2)``,
    ndof defaults to dof_offset + 3 n_nodes."""
    e, L = strand_geometry(nodes, elements)
    Ke = cable_stiffness(e, L, EA, tension)
    elements = np.asarray(elements, dtype=np.int64).reshape(-1, 2)
    dofs = (dof_offset + 3 * elements[:, :, None] + np.arange(3)).reshape(-1, 6)
    rows = np.repeat(dofs, 6, axis=1).ravel()
    cols = np.tile(dofs, (1, 6)).ravel()
    ndof = dof_offset + 3 * len(nodes) if ndof is None else ndof
    return sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(ndof, ndof))


def cable_tensions(e, L, EA, tension, u1, u2) -> np.ndarray:
    """Tension (ne,) N after the end displacements u1, u2 (ne, 3) m: T + EA / L · eᵀ (u2 − u1) (linear)."""
    e = np.atleast_2d(np.asarray(e, dtype=float))
    du = np.atleast_2d(np.asarray(u2, dtype=float) - np.asarray(u1, dtype=float))
    return np.asarray(tension, dtype=float) + np.asarray(EA, dtype=float) / np.asarray(L, dtype=float) * np.einsum(
        "ei,ei->e", e, du)
