"""Frictionless penalty contact on a small dense (condensed) stiffness: Newton on the contact energy.

For linear elastic bodies with a fixed penalty ε and multipliers λ (augmented Lagrangian, seed 004 §3.1)
the normal contact problem is the minimum of the convex, piecewise-quadratic energy

    Π(u) = ½ uᵀ S u − fᵀ u + Σ_i w_i / (2 ε_i) ⟨λ_i − ε_i g_i(u)⟩₊² ,   g = g0 + B u,

whose gradient is minus the out-of-balance force r = f + Bᵀ(w p) − S u with p = ⟨λ − ε g⟩₊ (the same
residual as :func:`femcheck.fe.newton.solve_contact`). The iteration is a semismooth (active-set) Newton
method with an **exact line search on Π**:

* direction d = H⁻¹ r, H = S + Bᵀ diag(w ε [closed]) B, the iteration matrix of the current active set,
  factorized densely (Cholesky) and **reused** while the active set does not change (modified N-R);
* the step α minimises Π(u + α d) exactly (Π' along d is monotone piecewise linear; bracketing plus
  bisection to round-off), so Π decreases at every iteration and the active set cannot cycle — this is
  what stops the chattering of a floating body (a cross in its 2c clearance) that a full step causes;
* where H is singular (a body held by no closed point, e.g. the cross before its pins seat) a small
  spring δ·I is added **to the iteration matrix only** (δ from 1e-10 of the largest diagonal, raised
  ×100 until the Cholesky succeeds). It never enters Π or r, so the converged state carries none of
  its force; ``stabilization_force_share`` = δ ‖d‖ / ‖f‖ of the last step before convergence (the force
  the spring would carry in the converged state; 0 when the final active set holds every body) is reported;
* initial active set: the points the caller predicts (``initial_closed``, e.g. the Hertz patch and the
  loaded lines of a pin in its bore); a wrong prediction only costs iterations;
* Uzawa updates λ ← p at the fixed penalty until the largest penetration is below ``penetration_tol``.

A solve that does not converge raises :class:`femcheck.errors.ConvergenceError` with the residual
history and the points whose status chattered (``detail["chattering"]``), never numbers.
"""
from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from femcheck.errors import ConvergenceError

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class CondensedContactResult:
    """Converged state of :func:`solve_condensed_contact` at each load factor.

    ``u`` (n_steps, n) m; ``pressure`` (n_steps, m) Pa; ``closed`` (n_steps, m) bool; ``iterations``,
    ``factorizations``, ``augmentations``, ``line_search_cuts`` (steps with α < 1) totals;
    ``residual_history`` ‖r‖ (N) per iteration; ``stabilized_iterations`` iterations whose matrix needed
    the spring; ``stabilization_force_share`` largest δ‖d‖/‖f‖ of the last step of a converged solve (module
    doc; 0 when its matrix had no spring); ``seconds``; ``low_rank_updates`` active-set changes solved by a
    Woodbury update of the last factorization instead of a new one.
    """

    u: np.ndarray
    pressure: np.ndarray
    closed: np.ndarray
    iterations: int
    factorizations: int
    augmentations: int
    line_search_cuts: int
    residual_history: tuple
    stabilized_iterations: int
    stabilization_force_share: float
    seconds: float
    low_rank_updates: int = 0


def _line_search(S_d_d: float, r_d: float, g, b, lam, eps, w) -> float:
    """α ≥ 0 minimising Π(u + α d): root of Π'(α) = −r·d + α dᵀSd − Σ w b (p(α) − p(0)) (monotone)."""
    p0 = np.maximum(lam - eps * g, 0.0)

    def dphi(a):
        p = np.maximum(lam - eps * (g + a * b), 0.0)
        return -r_d + a * S_d_d - float(np.dot(w * b, p - p0))

    lo, hi = 0.0, 1.0
    v = dphi(hi)
    if v <= 0.0:
        while v < 0.0:
            lo, hi = hi, 2.0 * hi
            if hi > 1e12:
                return np.inf  # Π unbounded along d: a mechanism no contact point resists
            v = dphi(hi)
        if v == 0.0:
            return hi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        if dphi(mid) < 0.0:
            lo = mid
        else:
            hi = mid
    # exact on the final linear piece: interpolate Π' between the bracket ends
    vlo, vhi = dphi(lo), dphi(hi)
    return hi if vhi == vlo else lo - vlo * (hi - lo) / (vhi - vlo)


def solve_condensed_contact(S: np.ndarray, f: np.ndarray, B, g0, eps, w, load_factors=(1.0,), *,
                            initial_closed=None, penetration_tol: float, rtol: float = 1e-9,
                            max_iter: int = 100, max_augment: int = 40, point_info=None,
                            low_rank_fraction: float = 0.08) -> CondensedContactResult:
    """Solve the frictionless contact problem on a dense stiffness (module doc).

    S (n, n) N/m symmetric positive semidefinite; f (n,) N at load factor 1; B (m, n) gap operator
    (g = g0 + B u, m); g0, eps (N/m³), w (m²) (m,); load_factors increasing, each a converged state;
    initial_closed (m,) bool, the predicted active set of the first iteration; penetration_tol (m);
    point_info callable(indices) -> list of dicts naming chattering points (for the error detail);
    low_rank_fraction: an active set that differs from the factorized one by at most this fraction of n
    points is solved by a Woodbury update of that factorization (``low_rank_updates``) instead of a new
    Cholesky (0 = always refactorize).
    """
    t0 = time.perf_counter()
    S = np.asarray(S, float)
    f = np.asarray(f, float)
    B = sp.csr_matrix(B)
    BT = sp.csr_matrix(B.T)
    g0, eps, w = (np.asarray(x, float) for x in (g0, eps, w))
    n, m = S.shape[0], g0.size
    u = np.zeros(n)
    lam = np.zeros(m)
    dmax = float(np.abs(np.diag(S)).max()) if n else 1.0
    closed_pred = np.zeros(m, bool) if initial_closed is None else np.asarray(initial_closed, bool)
    hist: list[float] = []
    status_hist: list[np.ndarray] = []
    nit = nfac = naug = ncut = nstab = 0
    stab_share = last_share = 0.0
    fac = fac_status = upd = None
    nupd = 0
    low_rank_max = int(low_rank_fraction * n)
    delta = 0.0
    out_u, out_p, out_c = [], [], []
    first = True
    for lf in load_factors:
        fl = lf * f
        fnorm = max(float(np.linalg.norm(fl)), 1e-300)
        for aug in range(max_augment + 1):
            converged = False
            prev = None
            for it in range(max_iter + 1):
                g = g0 + B @ u
                p = np.maximum(lam - eps * g, 0.0)
                r = fl + BT @ (w * p) - S @ u
                rn = float(np.linalg.norm(r))
                hist.append(rn)
                closed = p > 0.0
                if first:
                    closed = closed | closed_pred
                    first = False
                status_hist.append(closed)
                if prev is not None and np.array_equal(closed, prev) and rn <= rtol * fnorm:
                    converged = True
                    break
                if it == max_iter:
                    break
                if fac is not None and not np.array_equal(closed, fac_status) and low_rank_max > 0:
                    # the active set changed by k points: H = H_fac ± Σ b bᵀ w ε, solved by Woodbury on the
                    # factorization of H_fac while k ≤ low_rank_max (O(n² k) instead of O(n³) per change)
                    if upd is None or not np.array_equal(closed, upd[0]):
                        upd = _low_rank_update(fac, B, closed, fac_status, w, eps, low_rank_max)
                        nupd += upd is not None
                else:
                    upd = None
                if (fac is None or not np.array_equal(closed, fac_status)) and upd is None:
                    Bc = B[np.flatnonzero(closed)]
                    H = S + (Bc.T @ sp.diags(w[closed] * eps[closed]) @ Bc).toarray()
                    delta = 0.0
                    while True:
                        try:
                            fac = sla.cho_factor(H if delta == 0.0 else H + delta * np.eye(n), check_finite=False)
                            break
                        except np.linalg.LinAlgError:
                            delta = 1e-10 * dmax if delta == 0.0 else 100.0 * delta
                            if delta > 1e-2 * dmax:
                                raise ConvergenceError("contact iteration matrix is not positive definite even with "
                                                       f"a spring of {delta:.3g} N/m (an unsupported body)", hist)
                    fac_status = closed
                    nfac += 1
                # Newton step of the quadratic model of this active set: a predicted-closed point that is
                # still open contributes its linearised pressure λ − ε g (how a 2c clearance is crossed
                # in one step); kept only if it is a descent direction of Π, else the plain step
                pn = np.where(closed, lam - eps * g, p)
                d = _solve(fac, upd, fl + BT @ (w * pn) - S @ u)
                if float(r @ d) <= 0.0:
                    d = _solve(fac, upd, r)
                # the spring's force in this step; the one of the last step before convergence is what
                # it would carry in the converged state (reported; the residual r never contains it)
                last_share = delta * float(np.linalg.norm(d)) / fnorm
                nstab += delta > 0.0
                Sd = S @ d
                a = _line_search(float(d @ Sd), float(r @ d), g, B @ d, lam, eps, w)
                if not np.isfinite(a):
                    raise ConvergenceError(f"contact energy unbounded along the Newton direction at load factor {lf:g} "
                                           "(a mechanism no contact point resists)", hist)
                if a < 1.0 - 1e-12:
                    ncut += 1
                u = u + a * d
                prev = closed
                nit += 1
            if converged:
                stab_share = max(stab_share, last_share)
            if not converged:
                from femcheck.fe.contact import status as st
                bad = st.chattering([h.astype(np.int8) for h in status_hist[-12:]])
                detail = {"chattering": point_info(bad) if point_info else bad.tolist(), "n_chattering": int(bad.size)}
                raise ConvergenceError(f"contact Newton did not converge at load factor {lf:g} within {max_iter} "
                                       f"iterations (augmentation {aug}); {bad.size} points chatter", hist, detail)
            g = g0 + B @ u
            pen = float(max(-(g[p > 0]).min(), 0.0)) if np.any(p > 0) else 0.0
            if pen <= penetration_tol:
                break
            if aug == max_augment:
                raise ConvergenceError(f"augmented-Lagrangian updates left a penetration of {pen:.3g} m > "
                                       f"{penetration_tol:.3g} m after {max_augment} updates at load factor {lf:g}; "
                                       "raise the penalty", hist, {"penetration_m": pen})
            lam = p.copy()
            naug += 1
        log.info("load factor %.4g: %d iterations so far, %d factorizations, %d Uzawa updates, |r| %.3e, %d closed",
                 lf, nit, nfac, naug, hist[-1], int(np.count_nonzero(p > 0)))
        out_u.append(u.copy())
        out_p.append(p.copy())
        out_c.append(p > 0)
    return CondensedContactResult(np.array(out_u), np.array(out_p), np.array(out_c), nit, nfac, naug, ncut,
                                  tuple(hist), nstab, stab_share, time.perf_counter() - t0, nupd)


def _low_rank_update(fac, B, closed, fac_status, w, eps, k_max):
    """Woodbury data for H = H_fac + Uᵀ C U, U = B[changed] (k, n), C = ±diag(w ε) (+ closed since the
    factorization, − opened): (closed, Z = H_fac⁻¹ Uᵀ, U, M⁻¹-factor) or None when k > k_max or M is
    singular (then the caller refactorizes)."""
    changed = np.flatnonzero(closed != fac_status)
    if changed.size == 0 or changed.size > k_max:
        return None
    U = B[changed].toarray()
    c = np.where(closed[changed], 1.0, -1.0) * w[changed] * eps[changed]
    Z = sla.cho_solve(fac, U.T, check_finite=False)
    M = np.diag(1.0 / c) + U @ Z
    try:
        lu = sla.lu_factor(M, check_finite=False)
    except (np.linalg.LinAlgError, ValueError):
        return None
    if not np.all(np.isfinite(lu[0])) or np.min(np.abs(np.diag(lu[0]))) <= 1e-13 * np.max(np.abs(np.diag(lu[0]))):
        return None
    return closed.copy(), Z, U, lu


def _solve(fac, upd, y):
    """H⁻¹ y with the Cholesky factor of H_fac and, when given, its Woodbury update (:func:`_low_rank_update`)."""
    z = sla.cho_solve(fac, y, check_finite=False)
    if upd is None:
        return z
    _, Z, U, lu = upd
    return z - Z @ sla.lu_solve(lu, U @ z, check_finite=False)
