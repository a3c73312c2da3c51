"""Coulomb friction by a regularized stick / return-mapping slide law (seed 004 §3.2.2–3.2.3).

Tangential traction at a closed slave point (Pa, 2 components in the master frame t1, t2):

    trial      t_tr = λ_t + ε_t (s − s_ref)                 (s: relative slip B_t u, m)
    stick      ‖t_tr‖ ≤ μ p   →  t = t_tr                    (seed 004 eq. 18: the element acts as a spring)
    slide      ‖t_tr‖ > μ p   →  t = μ p t_tr / ‖t_tr‖       (eq. 19: force at the Coulomb limit along the slip)

λ_t and s_ref are the augmented-Lagrangian state (:mod:`augmented_lagrangian`): after the Uzawa update
λ_t is the converged traction and s_ref the slip it belongs to, so that at convergence a sticking point has
no relative slip left (independent of ε_t) and a sliding point carries exactly μ p. Open points carry none.

Forces: f_t = B_tᵀ (w t) (ndof,). Iteration matrix (kept within a load step by the modified Newton):
ε_t B_tᵀ W B_t on stick points and nothing on slide points (the exact slide tangent is unsymmetric
and changes every iteration; the modified Newton iteration converges without it for μ < 1).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from femcheck.fe.contact.status import OPEN, SLIDE, STICK


def return_mapping(slip, s_ref, lam_t, eps_t, mu: float, p):
    """Tangential traction and status.

    slip, s_ref, lam_t: (m, 2) m, m, Pa; eps_t (m,) Pa/m; mu ≥ 0; p (m,) Pa normal pressure (0 = open).
    Returns t (m, 2) Pa and status (m,) int8 (OPEN / STICK / SLIDE).
    """
    t_tr = lam_t + eps_t[:, None] * (slip - s_ref)
    norm = np.linalg.norm(t_tr, axis=1)
    limit = mu * p
    closed = p > 0
    slide = closed & ((norm > limit) | (limit <= 0.0))  # μ = 0: frictionless, always sliding
    t = np.where(slide[:, None], t_tr * (limit / np.where(norm > 0, norm, 1.0))[:, None], t_tr)
    t[~closed] = 0.0
    status = np.full(p.shape, OPEN, dtype=np.int8)
    status[closed] = STICK
    status[slide] = SLIDE
    return t, status


def tangential_force(B_t: sp.csr_matrix, weights: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Nodal forces B_tᵀ (w t) (ndof,) N; t (m, 2) Pa (row order of B_t: t1, t2 per point)."""
    return B_t.T @ (np.repeat(weights, 2) * t.ravel())


def tangential_stiffness(B_t: sp.csr_matrix, weights: np.ndarray, eps_t: np.ndarray, status: np.ndarray) -> sp.csr_matrix:
    """ε_t B_tᵀ W B_t over the sticking points (ndof × ndof) N/m."""
    d = np.repeat(weights * eps_t * (status == STICK), 2)
    return sp.csr_matrix(B_t.T @ sp.diags(d) @ B_t)


def slide_tangent(B_n: sp.csr_matrix, B_t: sp.csr_matrix, weights, eps_n, eps_t, mu: float, p, slip, s_ref, lam_t,
                  status) -> sp.csr_matrix:
    """Linearization of the sliding traction, B_tᵀ W ∂t/∂u over the sliding points (ndof × ndof) N/m.

    t = μ p t̂ with p = ⟨λ_n − ε_n g⟩₊ and t̂ = t_tr/‖t_tr‖ gives
    ∂t/∂u = −μ ε_n t̂ B_n + μ p ε_t/‖t_tr‖ (I − t̂ t̂ᵀ) B_t   (unsymmetric through the first term).
    Kept in the modified-Newton iteration matrix while the status is unchanged: without it the
    iteration diverges for sliding under a normal penalty (μ ε_n is as stiff as the penalty itself).
    """
    slide = np.flatnonzero(status == SLIDE)
    if mu <= 0 or slide.size == 0:
        n = B_n.shape[1]
        return sp.csr_matrix((n, n))
    t_tr = lam_t[slide] + eps_t[slide, None] * (slip[slide] - s_ref[slide])
    norm = np.maximum(np.linalg.norm(t_tr, axis=1), 1e-300)
    that = t_tr / norm[:, None]
    w = weights[slide]
    m = slide.size
    # coupling to the normal gap: (2m × m) block rows = −μ ε_n w t̂
    rows = np.arange(2 * m)
    cols = np.repeat(np.arange(m), 2)
    Cn = sp.csr_matrix((((-mu * eps_n[slide] * w)[:, None] * that).ravel(), (rows, cols)), shape=(2 * m, m))
    P = (mu * p[slide] * eps_t[slide] * w / norm)[:, None, None] * (np.eye(2)[None] - np.einsum("ij,ik->ijk", that, that))
    prow = np.repeat(np.arange(2 * m).reshape(m, 2), 2, axis=1).ravel()
    pcol = np.tile(np.arange(2 * m).reshape(m, 2), (1, 2)).ravel()
    Pt = sp.csr_matrix((P.ravel(), (prow, pcol)), shape=(2 * m, 2 * m))
    Bt_s = B_t[np.ravel(2 * slide[:, None] + np.arange(2)[None, :])]
    Bn_s = B_n[slide]
    return sp.csr_matrix(Bt_s.T @ (Cn @ Bn_s + Pt @ Bt_s))
