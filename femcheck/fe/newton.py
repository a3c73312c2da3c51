"""Modified Newton–Raphson for linear elasticity with penalty contact and Coulomb friction (seed 004 §3.3).

Problem (small strain, small sliding): find u = T q + λ g (constraints, :mod:`femcheck.fe.constraints`)
such that, at each load factor λ of the load steps, the reduced out-of-balance force vanishes,

    r(q) = Tᵀ [ λ f − K u + Σ_pairs ( B_nᵀ (w p) − B_tᵀ (w t) ) ] = 0          (N)

with the contact pressure p = ⟨λ_n − ε_n g⟩₊ and the friction traction t from the return mapping
(:mod:`femcheck.fe.contact.normal_penalty`, :mod:`femcheck.fe.contact.coulomb_friction`), g and s the gap
and slip of the paired slave integration points (:mod:`femcheck.fe.contact.pairing`).

Algorithm (seed 004 §3.3, Fig. 6; Bathe 1996 §8.4): for every load step (load increment),

1. evaluate the out-of-balance force r and the contact status (open / stick / slide) at the current q;
2. converged when ‖r‖ ≤ rtol · ‖reference force‖, ‖Δq‖ ≤ utol · ‖q‖ and the status did not change;
3. otherwise solve A Δq = r with the iteration matrix A = TᵀKT + Σ ε_n B_nᵀ W B_n (closed points)
   + Σ ε_t B_tᵀ W B_t (sticking points) [+ stabilising springs]. A is factorized once and **kept** while
   the status is unchanged (all later iterations and all Uzawa updates are back-substitutions) and
   **renewed** when the status changes or the iteration stagnates (‖r‖ not halved; the stabilising
   springs are then dropped). Small status changes (≤ ``max_lowrank`` constraint rows, frictionless
   pairs) are applied to the kept factorization exactly by a Sherman–Morrison–Woodbury correction
   instead of a renewal, as long as that is cheaper than a new factorization;
4. when the Newton loop has converged at fixed multipliers, the augmented-Lagrangian (Uzawa) update
   (:mod:`femcheck.fe.contact.augmented_lagrangian`) refreshes the multipliers until the largest
   penetration (and the residual slip of sticking points) is below ``penetration_tol`` — a tolerance
   in metres, independent of the penalty.

Force-driven bodies that touch nothing at the start (a sphere resting on a block) make TᵀKT singular until
contact closes. Two remedies, both without changing the converged answer: ``initial_closure`` (m) closes
every point whose initial gap is within that distance in the first iteration (an initial closure step),
and ``stabilization`` adds springs of that stiffness (relative to the mean diagonal of TᵀKT) to the
iteration matrix only — the residual never contains them, so they are "removed" at convergence.

Non-convergence raises :class:`femcheck.errors.ConvergenceError` with the residual history and, in
``detail``, the slave points whose status chatters (pair, point index, coordinates), never silent numbers.
"""
from __future__ import annotations

import dataclasses
import logging
import time
from typing import Sequence

import numpy as np
import scipy.sparse as sp

from femcheck.errors import ConvergenceError
from femcheck.fe.constraints import Constraints, none, pad
from femcheck.fe.contact import status as st
from femcheck.fe.contact.augmented_lagrangian import MultiplierState, constraint_violation, uzawa_update
from femcheck.fe.contact.coulomb_friction import return_mapping, slide_tangent, tangential_stiffness
from femcheck.fe.contact.normal_penalty import normal_stiffness, pressure
from femcheck.fe.contact.pairing import ContactPair
from femcheck.fe.linear_solver import factorize

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class ContactProblem:
    """Immutable description of a contact problem (SI units).

    K (n × n csr, N/m) elastic stiffness, n ≤ constraints.ndof (reference-node DOFs are zero-padded);
    f (n,) N external load at load factor 1; constraints u = T q + g (None = unconstrained), the prescribed
    part g is scaled with the load factor when ``scale_prescribed`` (displacement control);
    pairs: contact pairs from :func:`femcheck.fe.contact.pairing.pair_surfaces` built with ndof = the
    constrained system size.
    """

    K: sp.csr_matrix
    f: np.ndarray
    constraints: Constraints | None = None
    pairs: tuple[ContactPair, ...] = ()
    scale_prescribed: bool = True

    @property
    def ndof(self) -> int:
        return self.constraints.ndof if self.constraints is not None else self.K.shape[0]


@dataclasses.dataclass(frozen=True)
class PairState:
    """Contact state of one pair at a converged step: pressure (m,) Pa, traction (m, 2) Pa, gap (m,) m,
    slip (m, 2) m, status (m,) int8 (see :mod:`femcheck.fe.contact.status`)."""

    pressure: np.ndarray
    traction: np.ndarray
    gap: np.ndarray
    slip: np.ndarray
    status: np.ndarray

    def force(self, pair: ContactPair) -> float:
        """Total normal contact force Σ w p (N)."""
        return float(np.sum(pair.weights * self.pressure))


@dataclasses.dataclass(frozen=True)
class StepResult:
    """One converged load step: load_factor; u (ndof,) m; contact_force (ndof,) N (on the structure);
    pairs (per-pair :class:`PairState`); iterations (linear solves), factorizations, augmentations
    (Uzawa updates), residual_history (‖r‖ per iteration, N), seconds (wall)."""

    load_factor: float
    u: np.ndarray
    contact_force: np.ndarray
    pairs: tuple[PairState, ...]
    iterations: int
    factorizations: int
    augmentations: int
    residual_history: tuple[float, ...]
    seconds: float


@dataclasses.dataclass(frozen=True)
class ContactResult:
    """Result of :func:`solve_contact`: ``steps`` (one :class:`StepResult` per load step, the last is the
    final state); ``timings`` dict of seconds (reduce_s, factorize_s, solve_s, contact_s, total_s) and
    counts (factorizations, dofs, free_dofs); ``solver`` the linear-solver method used."""

    steps: tuple[StepResult, ...]
    timings: dict
    solver: str

    @property
    def u(self) -> np.ndarray:
        return self.steps[-1].u

    @property
    def pairs(self) -> tuple[PairState, ...]:
        return self.steps[-1].pairs

    @property
    def iterations_per_step(self) -> list[int]:
        return [s.iterations for s in self.steps]

    @property
    def residual_history(self) -> list[float]:
        return [r for s in self.steps for r in s.residual_history]

    def reactions(self, problem: ContactProblem, step: int = -1) -> np.ndarray:
        """Constraint reactions K u − λ f − f_contact (ndof,) N at the given step (nonzero at constrained DOFs)."""
        s = self.steps[step]
        K = pad(problem.K, problem.ndof)
        f = pad(np.asarray(problem.f, dtype=float), problem.ndof)
        return K @ s.u - s.load_factor * f - s.contact_force


def _load_factors(load_steps) -> list[float]:
    if np.ndim(load_steps) == 0:
        n = int(load_steps)
        if n < 1:
            raise ValueError(f"load_steps = {load_steps}; expected >= 1 or a sequence of load factors")
        return list(np.linspace(1.0 / n, 1.0, n))
    fac = [float(x) for x in load_steps]
    if not fac or any(x <= 0 for x in fac):
        raise ValueError(f"load_steps = {load_steps}; expected positive load factors")
    return fac


def solve_contact(problem: ContactProblem, load_steps: int | Sequence[float] = 1, *, rtol: float = 1e-8,
                  utol: float = 1e-8, penetration_tol: float | None = None, penetration_rtol: float = 1e-4,
                  max_iter: int = 60, max_augment: int = 40, stabilization: float = 0.0,
                  initial_closure: float = 0.0, method: str = "auto", max_lowrank: int = 100,
                  predictor: bool = False) -> ContactResult:
    """Solve ``problem`` by load increments with modified Newton–Raphson and Uzawa updates (see module doc).

    load_steps: number of equal increments or the load factors themselves (e.g. ``[0.3, 1.0]``; each step
    is a converged state in ``result.steps``). rtol: residual tolerance relative to the largest of the
    external, contact and internal force norms. utol: displacement-increment tolerance relative to ‖q‖.
    penetration_tol: m, largest penetration (and stick slip) accepted; default penetration_rtol · max|u|.
    stabilization: springs α · mean(diag TᵀKT) in the iteration matrix only (0 = none).
    initial_closure: m, points with initial gap ≤ this are closed in the first iteration.
    method: linear solver ("auto" | "pardiso" | "splu"; see :mod:`femcheck.fe.linear_solver`).
    predictor: start each load step from the last converged displacement scaled by the load-factor ratio.
    max_lowrank: status changes of up to this many constraint rows (a changed normal status = 1 row, a
    changed stick status = 2) are applied to the kept factorization by an exact low-rank
    (Sherman–Morrison–Woodbury) correction instead of a new factorization (0 = always refactorize); the
    factorization is renewed instead when the new back-substitutions would cost more than it did.
    """
    t_start = time.perf_counter()
    factors = _load_factors(load_steps)
    ndof = problem.ndof
    C = problem.constraints if problem.constraints is not None else none(ndof)
    K = pad(sp.csr_matrix(problem.K), ndof)
    f = pad(np.asarray(problem.f, dtype=float), ndof)
    T = C.T
    t0 = time.perf_counter()
    Kr = sp.csr_matrix(T.T @ (K @ T))
    fr1 = T.T @ (f - K @ C.g)  # reduced load at load factor 1 (prescribed part included)
    fr_fixed = np.zeros_like(fr1)
    if not problem.scale_prescribed:
        fr1, fr_fixed = T.T @ f, -(T.T @ (K @ C.g))
    pairs = list(problem.pairs)
    Bn = [sp.csr_matrix(p.B_n @ T) for p in pairs]
    Bt = [sp.csr_matrix(p.B_t @ T) for p in pairs]
    gn_g = [p.B_n @ C.g for p in pairs]
    gt_g = [(p.B_t @ C.g).reshape(-1, 2) for p in pairs]
    reduce_s = time.perf_counter() - t0
    diag_mean = float(np.mean(np.abs(Kr.diagonal()))) if Kr.shape[0] else 1.0
    stab = sp.identity(Kr.shape[0], format="csr") * (stabilization * diag_mean) if stabilization > 0 else None

    q = np.zeros(Kr.shape[0])
    states = [MultiplierState.zeros(p.n_points) for p in pairs]
    timings = dict(reduce_s=reduce_s, factorize_s=0.0, lowrank_s=0.0, solve_s=0.0, contact_s=0.0,
                   factorizations=0)
    solver_method = ""
    steps = []
    first_iteration = True

    def evaluate(lf):
        """Out-of-balance force, per-pair (p, t, gap, slip, status) at q and load factor lf."""
        tc = time.perf_counter()
        scale_g = lf if problem.scale_prescribed else 1.0
        r = lf * fr1 + fr_fixed - Kr @ q
        fc_norm = 0.0
        out = []
        for k, pair in enumerate(pairs):
            gap = pair.g0 + Bn[k] @ q + scale_g * gn_g[k]
            slip = (Bt[k] @ q).reshape(-1, 2) + scale_g * gt_g[k]
            s = states[k]
            p = pressure(gap, s.lam_n, pair.penalty_n)
            t, status = return_mapping(slip, s.s_ref, s.lam_t, pair.penalty_t, pair.friction, p)
            fc = Bn[k].T @ (pair.weights * p) - Bt[k].T @ (np.repeat(pair.weights, 2) * t.ravel())
            fc_norm = max(fc_norm, float(_norm(fc)))
            r += fc
            out.append((p, t, gap, slip, status))
        timings["contact_s"] += time.perf_counter() - tc
        return r, out, fc_norm

    fac = None
    fac_key = None
    Bn_all = sp.vstack(Bn, format="csr") if pairs else None
    Bt_all = sp.vstack(Bt, format="csr") if pairs else None
    wn_all = np.concatenate([p.weights * p.penalty_n for p in pairs]) if pairs else None
    wt_all = np.concatenate([p.weights * p.penalty_t for p in pairs]) if pairs else None
    lf_prev = None
    for lf in factors:
        t_step = time.perf_counter()
        if lf_prev is not None and predictor:
            q = q * (lf / lf_prev)  # proportional predictor from the last converged step
        lf_prev = lf
        hist: list[float] = []
        iters = nfac = naug = 0
        status_hist: list[np.ndarray] = []
        for aug in range(max_augment + 1):
            prev_status = None
            dq_norm = np.inf
            converged = False
            r_prev = np.inf
            use_stab = stab is not None
            for it in range(max_iter + 1):
                r, ev, fc_norm = evaluate(lf)
                rn = float(_norm(r))
                hist.append(rn)
                if first_iteration and initial_closure > 0:
                    # initial closure step: points within initial_closure of touching start closed
                    ev = [(p_, t_, g_, s_, np.where((pair.g0 <= initial_closure) & (sta == st.OPEN),
                                                         st.STICK if pair.friction > 0 else st.SLIDE, sta))
                          for pair, (p_, t_, g_, s_, sta) in zip(pairs, ev)]
                status_all = np.concatenate([e[4] for e in ev]) if ev else np.zeros(0, np.int8)
                status_hist.append(status_all)
                if log.isEnabledFor(logging.DEBUG):
                    nchg = -1 if prev_status is None else int(np.count_nonzero(status_all != prev_status))
                    log.debug("lf %.3g aug %d it %d |r| %.3e status changes %d closed %d", lf, aug, it, rn, nchg,
                              int(np.count_nonzero(status_all > 0)))
                ref = max(float(_norm(lf * fr1 + fr_fixed)), fc_norm, float(_norm(Kr @ q)), 1e-300)
                same = prev_status is not None and np.array_equal(status_all, prev_status)
                if same and rn <= rtol * ref and dq_norm <= utol * max(_norm(q), 1e-300):
                    converged = True
                    break
                if it == max_iter:
                    break
                key = status_all.tobytes()
                stagnating = same and rn > 0.5 * r_prev and rn > rtol * ref
                renew = fac is None or stagnating
                if not renew and key != fac_key:
                    tl = time.perf_counter()
                    renew = not fac.set_status(status_all)
                    timings["lowrank_s"] += time.perf_counter() - tl
                if renew:
                    if stagnating:
                        use_stab = False
                    A = Kr
                    symmetric = True
                    for k, pair in enumerate(pairs):
                        s_k = ev[k][4]
                        A = A + normal_stiffness(Bn[k], pair.weights, pair.penalty_n, s_k > 0)
                        A = A + tangential_stiffness(Bt[k], pair.weights, pair.penalty_t, s_k)
                        if pair.friction > 0 and np.any(s_k == st.SLIDE):
                            sk = states[k]
                            A = A + slide_tangent(Bn[k], Bt[k], pair.weights, pair.penalty_n, pair.penalty_t,
                                                  pair.friction, ev[k][0], ev[k][3], sk.s_ref, sk.lam_t, s_k)
                            symmetric = False
                    if use_stab:
                        A = A + stab
                    base = factorize(A, method, symmetric=symmetric)
                    # friction: a stick/slide change alters the slide tangent, so no low-rank updates
                    fac = _LowRankUpdated(base, status_all, Bn_all, Bt_all, wn_all, wt_all,
                                          0 if any(p.friction > 0 for p in pairs) else max_lowrank)
                    solver_method = base.method
                    timings["factorize_s"] += base.seconds
                    timings["factorizations"] += 1
                    nfac += 1
                fac_key = key
                ts = time.perf_counter()
                dq = fac.solve(r)
                timings["solve_s"] += time.perf_counter() - ts
                q = q + dq
                dq_norm = float(_norm(dq))
                iters += 1
                prev_status = status_all
                r_prev = rn
                first_iteration = False
            if not converged:
                bad = st.chattering(status_hist[-12:])
                detail = _chatter_detail(pairs, bad)
                raise ConvergenceError(
                    f"modified Newton-Raphson did not converge at load factor {lf:g} within {max_iter} "
                    f"iterations (augmentation {aug}); {bad.size} slave points chatter", hist, detail)
            # augmented-Lagrangian check / update
            u_full = T @ q + (lf if problem.scale_prescribed else 1.0) * C.g
            tol = penetration_tol if penetration_tol is not None else penetration_rtol * max(np.abs(u_full).max(), 1e-300)
            worst = 0.0
            for k, pair in enumerate(pairs):
                p, t, gap, slip, status = ev[k]
                pen, slip_err = constraint_violation(gap, slip, states[k], status)
                worst = max(worst, pen, slip_err if pair.friction > 0 else 0.0)
            if worst <= tol or not pairs:
                break
            if aug == max_augment:
                raise ConvergenceError(
                    f"augmented-Lagrangian updates did not bring the penetration below {tol:.3g} m in "
                    f"{max_augment} updates at load factor {lf:g} (worst {worst:.3g} m); raise the penalty",
                    hist, {"penetration_m": worst})
            for k, pair in enumerate(pairs):
                p, t, gap, slip, status = ev[k]
                states[k] = uzawa_update(states[k], gap, slip, pair.penalty_n, pair.penalty_t, pair.friction)
            naug += 1
        u_full = T @ q + (lf if problem.scale_prescribed else 1.0) * C.g
        fc_full = np.zeros(ndof)
        pstates = []
        for k, pair in enumerate(pairs):
            p, t, gap, slip, status = ev[k]
            fc_full += pair.B_n.T @ (pair.weights * p) - pair.B_t.T @ (np.repeat(pair.weights, 2) * t.ravel())
            pstates.append(PairState(pressure=p, traction=t, gap=gap, slip=slip, status=status))
        steps.append(StepResult(load_factor=lf, u=u_full, contact_force=fc_full, pairs=tuple(pstates),
                                iterations=iters, factorizations=nfac, augmentations=naug,
                                residual_history=tuple(hist), seconds=time.perf_counter() - t_step))
        log.info("load factor %.4g: %d iterations, %d factorizations, %d Uzawa updates, |r| %.3e, status %s",
                 lf, iters, nfac, naug, hist[-1],
                 [st.counts(ps.status) for ps in pstates])
    timings["total_s"] = time.perf_counter() - t_start
    timings["dofs"] = ndof
    timings["free_dofs"] = int(Kr.shape[0])
    return ContactResult(steps=tuple(steps), timings=timings, solver=solver_method)


def _norm(x) -> float:
    """Euclidean norm without BLAS (BLAS threads spin on an oversubscribed machine)."""
    x = np.asarray(x, dtype=float)
    return float(np.sqrt(np.sum(x * x)))


class _LowRankUpdated:
    """Kept factorization of A(status₀) with exact solves for A(status) = A(status₀) + U D Uᵀ (Woodbury).

    U holds the reduced constraint rows (B_n rows of points whose closed state changed, B_t rows of points
    whose stick state changed) as columns, D = ±ε w (+ newly active, − released). A⁻¹U is computed once
    per row by back-substitution and cached; S = D⁻¹ + UᵀA⁻¹U (k × k) is factorized densely.
    """

    def __init__(self, base, status, Bn, Bt, wn, wt, max_rank: int):
        self.base, self.status0 = base, np.asarray(status).copy()
        self.Bn, self.Bt, self.wn, self.wt = Bn, Bt, wn, wt
        self.max_rank = int(max_rank)
        self.method = base.method
        self._cache: dict = {}
        self._U = self._Z = self._S = None
        self._t_col = None  # measured back-substitution time per column (s)

    def set_status(self, status) -> bool:
        """Prepare solves for ``status``; False when the change exceeds ``max_rank`` rows (refactorize)."""
        from scipy.linalg import lu_factor

        closed0, closed = self.status0 > 0, status > 0
        stick0, stick = self.status0 == st.STICK, status == st.STICK
        i_n = np.flatnonzero(closed0 != closed)
        i_t = np.flatnonzero(stick0 != stick)
        k = i_n.size + 2 * i_t.size
        if k == 0:
            self._U = None
            return True
        if k > self.max_rank:
            return False
        keys = [("n", int(i)) for i in i_n] + [("t", int(2 * i + c)) for i in i_t for c in (0, 1)]
        rows_n = self.Bn[i_n] if i_n.size else None
        rows_t = self.Bt[np.ravel(2 * i_t[:, None] + np.arange(2)[None, :])] if i_t.size else None
        Ut = sp.vstack([r for r in (rows_n, rows_t) if r is not None], format="csr")  # k × n, sparse
        d = np.r_[np.where(closed[i_n], 1.0, -1.0) * self.wn[i_n],
                  np.repeat(np.where(stick[i_t], 1.0, -1.0) * self.wt[i_t], 2)]
        missing = [j for j, key in enumerate(keys) if key not in self._cache]
        if missing and self._t_col is not None and len(missing) * self._t_col > self.base.seconds:
            return False  # cheaper to refactorize than to back-substitute that many new columns
        if missing:
            t0 = time.perf_counter()
            Zm = self.base.solve(Ut[missing].T.toarray()).reshape(Ut.shape[1], len(missing))
            self._t_col = (time.perf_counter() - t0) / len(missing)
            for col, j in enumerate(missing):
                self._cache[keys[j]] = Zm[:, col]
        Z = np.column_stack([self._cache[key] for key in keys])
        S = np.diag(1.0 / d) + Ut @ Z
        self._U, self._Z, self._S = Ut, Z, lu_factor(S)
        return True

    def solve(self, b):
        from scipy.linalg import lu_solve

        y = self.base.solve(b)
        if self._U is None:
            return y
        return y - self._Z @ lu_solve(self._S, self._U @ y)


def _chatter_detail(pairs, bad_global: np.ndarray) -> dict:
    """{"chattering": [{"pair", "point", "x_m"}...]} for the global point indices in ``bad_global``."""
    out = []
    offset = 0
    for pair in pairs:
        sel = bad_global[(bad_global >= offset) & (bad_global < offset + pair.n_points)] - offset
        for i in sel[:50]:
            out.append({"pair": pair.name, "point": int(i), "x_m": pair.points[i].tolist(),
                        "slave_facet": int(pair.slave_facet[i])})
        offset += pair.n_points
    return {"chattering": out, "n_chattering": int(bad_global.size)}
