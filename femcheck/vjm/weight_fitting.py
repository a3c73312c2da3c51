"""Stiffness-model fitting with a positive diagonal weight matrix, and linear fine-tuning (seed 001 sec. 3).

Fitting (seed 001 eqs. 10-12). The initial virtual-joint stiffness K_theta (from FEA / link tests) is scaled
by a diagonal matrix W with positive entries, ``K'_theta = W K_theta W^T`` (eq. 10; positive w keeps K'
positive definite). The entries of W are tied to few free weights by a map (eq. 12: 18 diagonal entries,
11 free weights, axial terms fixed to 1). The cost over m measurements (eq. 11)::

    E = sum e^T L e,    e = (sum_i K_i(W))^-1 F_exp - dX_exp

is minimized over log(w) (so w > 0) with a bounded trust-region least-squares solver from several
deterministic starts (start 0 at w = 1, the seed's choice; the others log-uniform in [0.01, 10]), with an
exact Jacobian when the model gives one. Which weights the data identify is judged three ways:

* structurally: the weight lies in the null space of d(residual)/d(log w) (no data of this design see it);
* statistically: the 95 % interval of the weight, the hull over every minimum that fits the data as well
  as the best one (likelihood-ratio bound), spans more than a factor 4;
* as in the seed (Table 2): the variance of the weight over the best runs exceeds a threshold (0.1).

A seed-style run spread alone cannot tell a flat direction from a start that did not converge; only runs
that converged to an equally good minimum enter it here.

Fine-tuning (seed 001 sec. 3.3). The fitted model's outputs x are mapped by a first-degree correction
``x' = a x + b`` per output component (and per norm), a and b from a least-squares line through
(model, measured) pairs (seed 001 Fig. 6, Table 3).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Callable

import numpy as np

log = logging.getLogger(__name__)

#: seed 001 eq. 12: diagonal of W for links 1-3 (6 entries each) as indices into the 11 free weights; -1 = fixed at 1
HISS_WEIGHT_MAP = (-1, 0, 0, 1, 2, 2, -1, 3, 4, 5, 6, 7, -1, 8, 8, 9, 10, 10)


def expand_weights(w: np.ndarray, weight_map) -> np.ndarray:
    """Diagonal of W (len(map),) from the free weights ``w`` (p,) (entries with map -1 are 1)."""
    idx = np.asarray(weight_map)
    return np.where(idx < 0, 1.0, np.asarray(w, dtype=float)[np.clip(idx, 0, None)])


#: the two readings of seed 001 eq. 10, as the exponent of w in a diagonal stiffness entry: ``quadratic`` is
#: ``K' = W K W^T`` as printed (K'_jj = w^2 K_jj), ``linear`` is ``K' = W^1/2 K W^1/2`` (K'_jj = w K_jj, the
#: weight a stiffness factor). The case key ``[fitting] stiffness_scaling`` chooses; ``hiss_column_consistency``
#: says which one the paper's own Table 2 supports.
STIFFNESS_EXPONENT = {"linear": 1.0, "quadratic": 2.0}


def weight_factors(w: np.ndarray, weight_map, reading: str = "quadratic") -> np.ndarray:
    """Diagonal d (len(map),) of the congruence ``K' = D K D`` for the eq. 10 ``reading``: expand_weights(w)^(e/2)."""
    return expand_weights(w, weight_map) ** (STIFFNESS_EXPONENT[reading] / 2)


def scaled_stiffness(K_theta: np.ndarray, w: np.ndarray, weight_map, reading: str = "quadratic") -> np.ndarray:
    """K' = D K D with D = diag(weight_factors(w)) (seed 001 eq. 10; ``quadratic``: D = W, as printed)."""
    d = weight_factors(w, weight_map, reading)
    return d[:, None] * K_theta * d[None, :]


@dataclass(frozen=True)
class WeightFit:
    """Result of :func:`fit_weights`.

    ``weights`` (p,) best fit; ``cost`` its E; ``runs`` (r, p) weights of every start, ``run_costs`` (r,).
    ``converged``: the runs as good as the best in the statistical sense, ``E - E_best <= s^2 chi2_0.95(rank)``
    (the 95 % likelihood-ratio region, ``s^2 = E_best / (n - rank)``), plus round-off; with noise-free data
    only runs at the best minimum itself. ``top``: the (at most ``top``) lowest-cost of them, over which
    ``variance`` (p,) of each weight is taken (seed 001 Table 2 takes the five best runs).
    ``sensitivity`` (p,): norm of d(residual)/d(log w) at the best fit relative to the largest.
    ``structural`` (p,) bool: the weight has a component in the null space of that Jacobian (no data of this
    design can identify it). ``sd_log`` (p,): standard error of log w at the best fit, Gauss-Newton
    ``s^2 (J^T J)^+`` (inf for structural weights). ``ci_low``, ``ci_high`` (p,): 95 % interval, the hull of
    ``w exp(-+1.96 sd_log)`` over the converged runs (so distinct equally good minima widen it).
    ``at_bound`` (p,) bool. ``unidentifiable`` (p,) bool: structural, or ``ci_high / ci_low`` above
    ``ci_ratio_threshold`` (4: not known to within a factor 2 either way), or at a bound, or ``variance``
    above ``variance_threshold`` (0.1, seed 001's criterion). ``reasons``: per weight, the criteria that hold
    (also "distinct equivalent minima" when converged runs differ by more than 5 %, informative only).
    """

    weights: np.ndarray
    cost: float
    runs: np.ndarray
    run_costs: np.ndarray
    converged: np.ndarray
    top: np.ndarray
    variance: np.ndarray
    sensitivity: np.ndarray
    structural: np.ndarray
    sd_log: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray
    at_bound: np.ndarray
    unidentifiable: np.ndarray
    reasons: tuple

    @property
    def n_runs(self) -> int:
        return len(self.run_costs)


def fit_weights(predict: Callable[[np.ndarray], np.ndarray], measured: np.ndarray, n_weights: int, *,
                error_weight=None, restarts: int = 8, top: int = 5, variance_threshold: float = 0.1,
                bounds=(1e-3, 1e3), seed: int = 0, jacobian: Callable | None = None,
                start_range=(0.01, 10.0), min_converged: int = 1, max_restarts: int | None = None,
                converged_rtol: float = 1e-6, ci_ratio_threshold: float = 4.0,
                null_rtol: float = 1e-7, profile: bool = False) -> WeightFit:
    """Fit positive weights w (n_weights,) so that ``predict(w)`` (N, 6) matches ``measured`` (N, 6) (seed 001 eq. 11).

    ``error_weight``: diagonal of L (k,) (default identity; 1/sigma^2 whitens the residuals);
    ``jacobian(w)``: optional d predict / d log w (N, k, p) (else finite differences);
    ``restarts`` starts, the first at w = 1 (the seed's choice), the others log-uniform in ``start_range``
    (within ``bounds``) from ``numpy.random.default_rng(seed)`` (deterministic). If fewer than ``min_converged`` runs reach the best
    cost, further starts are made around the best fit (log-normal, sd 0.5) until they do or ``max_restarts``
    (default 4 x restarts) runs were made; this shows how far flat directions let the weights drift.
    ``profile``: 95 % intervals from the profile likelihood (each weight held at a value, the others refitted,
    until the cost rises by s^2 chi2_1(0.95)); else from the local Gauss-Newton covariance, which can be far
    too narrow for a weakly seen weight (the cost is not quadratic in log w there).
    """
    from scipy.optimize import least_squares

    measured = np.asarray(measured, dtype=float)
    Lsqrt = np.sqrt(np.ones(measured.shape[1]) if error_weight is None else np.asarray(error_weight, dtype=float))
    lo, hi = np.log(bounds[0]), np.log(bounds[1])
    max_restarts = 4 * restarts if max_restarts is None else max(max_restarts, restarts)
    max_nfev = 60 * (n_weights + 1)

    def residual(s):
        return ((predict(np.exp(s)) - measured) * Lsqrt).ravel()

    jac = None
    if jacobian is not None:
        def jac(s):
            return (np.asarray(jacobian(np.exp(s))) * Lsqrt[None, :, None]).reshape(-1, n_weights)

    rng = np.random.default_rng(seed)
    runs, costs = [], []

    def run(s0):
        s0 = np.clip(s0, lo + 1e-9, hi - 1e-9)
        sol = least_squares(residual, s0, jac=jac if jac is not None else "2-point", bounds=(lo, hi), method="trf",
                            x_scale=1.0, xtol=1e-12, ftol=1e-14, gtol=1e-14, max_nfev=max_nfev)
        runs.append(sol.x)
        costs.append(2.0 * sol.cost)                     # E = sum e^T L e
        log.debug("start %d: E = %.6e after %d evaluations", len(runs), costs[-1], sol.nfev)

    s_lo, s_hi = max(np.log(start_range[0]), lo), min(np.log(start_range[1]), hi)     # starts inside the bounds
    run(np.zeros(n_weights))
    for _ in range(restarts - 1):
        run(rng.uniform(s_lo, s_hi, n_weights))
    E0 = float(np.sum((measured * Lsqrt) ** 2))

    def converged_set():
        c = np.array(costs)
        return np.flatnonzero(c <= c.min() * (1 + converged_rtol) + 1e-12 * E0)

    while len(converged_set()) < min_converged and len(runs) < max_restarts:
        best_s = runs[int(np.argmin(costs))]
        run(best_s + rng.normal(0.0, 0.5, n_weights))
    S, costs = np.array(runs), np.array(costs)
    W = np.exp(S)
    best = int(np.argmin(costs))

    def local_jacobian(s):
        if jac is not None:
            return jac(s)
        h = 1e-5
        return np.column_stack([(residual(s + h * e) - residual(s - h * e)) / (2 * h) for e in np.eye(n_weights)])

    # local identifiability at the best fit: Gauss-Newton covariance of log w, s^2 (J^T J)^+
    Jw = local_jacobian(S[best])
    col = np.linalg.norm(Jw, axis=0)
    sens = col / max(float(col.max()), np.finfo(float).tiny)

    def null_of(Jl):
        _, svl, Vl = np.linalg.svd(Jl, full_matrices=False)
        r = int(np.sum(svl > null_rtol * svl[0])) if svl.size and svl[0] > 0 else 0
        return r, np.sum(Vl[r:] ** 2, axis=0) > 1e-6

    rank, unseen = null_of(Jw)
    # structural: unseen at the fit and at the nominal w = 1 (a weight driven to a bound is unseen there only)
    structural = unseen & null_of(local_jacobian(np.zeros(n_weights)))[1]
    s2 = float(costs[best]) / max(Jw.shape[0] - rank, 1)

    def local_sd(Jl):
        r, nul = null_of(Jl)
        _, svl, Vl = np.linalg.svd(Jl, full_matrices=False)
        cov = (Vl[:r].T / svl[:r] ** 2) @ Vl[:r] * s2
        return np.where(nul, np.inf, np.sqrt(np.clip(np.diag(cov), 0, None)))

    # runs statistically as good as the best: E - E_best within the 95 % likelihood-ratio bound of one weight,
    # s^2 chi2_1(0.95) (plus round-off); distinct minima among them mean the data cannot choose between them
    from scipy.stats import chi2
    delta = s2 * float(chi2.ppf(0.95, 1))
    conv = np.flatnonzero(costs <= costs[best] * (1 + converged_rtol) + 1e-12 * E0 + delta)
    conv = conv[np.argsort(costs[conv])]
    used = conv[: max(1, top)]
    var = np.var(W[used], axis=0, ddof=1) if len(used) > 1 else np.zeros(n_weights)
    # distinct minima among them (seen weights differ by more than 5 %), the profiles start from the best two
    distinct = []
    for r in conv:
        if all(np.max(np.abs(S[r] - S[q])[~structural], initial=0.0) > np.log(1.05) for q in distinct):
            distinct.append(r)
    sd = local_sd(Jw)
    # a profile is only meaningful above the round-off of the cost (noise-free data: the point itself)
    profile = profile and delta > 1e-9 * E0
    with np.errstate(over="ignore"):
        ci_lo, ci_hi = W[best].copy(), W[best].copy()
        for r in distinct[:2] if profile else conv:
            sd_r = sd if r == best else local_sd(local_jacobian(S[r]))
            if profile:
                # 95 % profile-likelihood interval of each weight around this minimum
                ends = np.array([[_profile_end(residual, jac, S[r], float(costs[best]), k, side, delta, float(sd_r[k]),
                                               (lo, hi), E_start=float(costs[r])) for side in (-1, 1)]
                                 if not structural[k] else [-np.inf, np.inf] for k in range(n_weights)])
                lo_r, hi_r = np.exp(ends[:, 0]), np.exp(ends[:, 1])
            else:
                lo_r, hi_r = W[r] * np.exp(-1.96 * sd_r), W[r] * np.exp(1.96 * sd_r)
            ci_lo, ci_hi = np.minimum(ci_lo, lo_r), np.maximum(ci_hi, hi_r)
        for r in conv:                                   # every equally good run lies inside
            ci_lo, ci_hi = np.minimum(ci_lo, W[r]), np.maximum(ci_hi, W[r])
        ci_lo, ci_hi = np.where(structural, 0.0, ci_lo), np.where(structural, np.inf, ci_hi)
        ratio = ci_hi / ci_lo
    at_bound = (S[best] <= lo + 1e-6) | (S[best] >= hi - 1e-6)
    at_bound |= ~structural & ((ci_lo <= np.exp(lo) * (1 + 1e-6)) | (ci_hi >= np.exp(hi) * (1 - 1e-6)))
    wide = ~structural & ~(ratio <= ci_ratio_threshold)
    spread = var > variance_threshold
    multi = ~structural & (np.ptp(S[conv], axis=0) > np.log(1.05)) if len(conv) > 1 else np.zeros(n_weights, bool)
    reasons = tuple(tuple(r for r, f in (("structural", structural[k]), ("wide interval", wide[k]),
                                         ("distinct equivalent minima", multi[k]), ("at bound", at_bound[k]),
                                         ("restart spread", spread[k])) if f)
                    for k in range(n_weights))
    return WeightFit(weights=W[best], cost=float(costs[best]), runs=W, run_costs=costs, converged=conv, top=used,
                     variance=var, sensitivity=sens, structural=structural, sd_log=sd, ci_low=ci_lo, ci_high=ci_hi,
                     at_bound=at_bound, unidentifiable=structural | wide | at_bound | spread, reasons=reasons)


def _profile_end(residual, jac, s_best, E_best, k, side, delta, sd_k, bounds, rel=0.1, max_fits=14, E_start=None):
    """End (log w_k) of the 95 % profile-likelihood interval of weight k on one side (-1 / +1).

    Holds s_k = s_best_k + side t and refits the others (warm starts); finds t where the cost rises to
    ``E_best + delta`` (``s_best`` may be another minimum, of cost ``E_start``, as good as the best). A
    quadratic profile ends at the Gauss-Newton 1.96 sd: when the rise there is within a factor 2 of ``delta``
    the end is interpolated as for a parabola; otherwise it is bracketed by doubling and bisected to ``rel``
    of t.
    Returns the bound when the cost never rises enough before it (the interval is open there).
    """
    from scipy.optimize import least_squares

    lo, hi = bounds
    p = len(s_best)
    free = np.arange(p) != k
    room = (hi - s_best[k]) if side > 0 else (s_best[k] - lo)
    state = {"z": s_best[free].copy()}

    def excess(t):
        sk = s_best[k] + side * t

        def full(z):
            s = np.empty(p); s[free] = z; s[k] = sk
            return s

        kw = {"jac": (lambda z: jac(full(z))[:, free])} if jac is not None else {}
        sol = least_squares(lambda z: residual(full(z)), state["z"], bounds=(lo, hi), method="trf",
                            xtol=1e-10, ftol=1e-12, gtol=1e-12, max_nfev=30 * p, **kw)
        state["z"] = sol.x
        return (2.0 * sol.cost - E_best) / delta if delta > 0 else np.inf

    if room <= 1e-9:
        return s_best[k] + side * room
    if E_start is not None and E_start > E_best:         # another minimum: its own quadratic guess shrinks
        sd_k = sd_k * np.sqrt(max(1.0 - (E_start - E_best) / delta, 1e-4)) if delta > 0 else sd_k
    t = min(1.96 * sd_k if np.isfinite(sd_k) and sd_k > 0 else 0.1, room)
    t = max(t, 1e-9)
    r = excess(t)
    fits = 1
    if 0.5 <= r <= 2.0 and t < room:
        return s_best[k] + side * t / np.sqrt(r)
    t_in, t_out = 0.0, None
    if r < 1:
        t_in = t
        while fits < max_fits:
            if t >= room:
                return s_best[k] + side * room
            t = min(2 * t, room)
            r = excess(t); fits += 1
            if r >= 1:
                t_out = t
                break
            t_in = t
        else:
            return s_best[k] + side * t
    else:
        t_out = t
    while fits < max_fits and t_out - t_in > rel * t_out:
        t = 0.5 * (t_in + t_out)
        r = excess(t); fits += 1
        if r < 1:
            t_in = t
        else:
            t_out = t
    return s_best[k] + side * 0.5 * (t_in + t_out)


@dataclass(frozen=True)
class FineTuning:
    """Per-component correction x' = a x + b (seed 001 sec. 3.3, Table 3): ``a``, ``b`` (k,);
    ``rms_before``, ``rms_after`` (k,) of (model - measured)."""

    a: np.ndarray
    b: np.ndarray
    rms_before: np.ndarray
    rms_after: np.ndarray

    def apply(self, x: np.ndarray) -> np.ndarray:
        return self.a * np.asarray(x, dtype=float) + self.b


def fine_tune(model: np.ndarray, measured: np.ndarray) -> FineTuning:
    """Least-squares line measured ~ a model + b for each column of ``model``, ``measured`` (N, k)."""
    x = np.asarray(model, dtype=float)
    y = np.asarray(measured, dtype=float)
    xm, ym = x.mean(0), y.mean(0)
    sxx = np.sum((x - xm) ** 2, axis=0)
    a = np.where(sxx > 0, np.sum((x - xm) * (y - ym), axis=0) / np.where(sxx > 0, sxx, 1.0), 1.0)
    b = ym - a * xm
    before = np.sqrt(np.mean((x - y) ** 2, axis=0))
    after = np.sqrt(np.mean((a * x + b - y) ** 2, axis=0))
    return FineTuning(a=a, b=b, rms_before=before, rms_after=after)


def with_norms(twists: np.ndarray) -> np.ndarray:
    """(N, 6) twists -> (N, 8) with |d|_xyz and |theta|_abg appended (the extra rows of seed 001 Table 3)."""
    t = np.asarray(twists, dtype=float)
    return np.column_stack([t, np.linalg.norm(t[:, :3], axis=1), np.linalg.norm(t[:, 3:], axis=1)])


def error_statistics(error: np.ndarray) -> dict:
    """Seed 001 Table 4 statistics of errors (N, k) per column: ``rms``, ``std`` (n-1, MATLAB's ``std``; the
    published Table 4 only fits n-1: its corrected rows have Std > RMS with M = 0), ``mean``, ``abs_mean``."""
    e = np.asarray(error, dtype=float)
    n = e.shape[0]
    return {"rms": np.sqrt(np.mean(e ** 2, axis=0)), "std": np.std(e, axis=0, ddof=1) if n > 1 else np.zeros(e.shape[1]),
            "mean": e.mean(axis=0), "abs_mean": np.mean(np.abs(e), axis=0)}


@dataclass(frozen=True)
class SeedCorrection:
    """Seed 001 sec. 5.2 two-level correction. ``a``, ``b`` (8,): the lines of Table 3 for dx, dy, dz, dalpha,
    dbeta, dgamma, |d|_xyz, |theta|_abg; ``fitted_error``, ``tuned_error`` (N, 8): model - measured before and
    after the correction (Table 4's "fitted" and "fine-tuned" model)."""

    a: np.ndarray
    b: np.ndarray
    fitted_error: np.ndarray
    tuned_error: np.ndarray


def seed_correction(model: np.ndarray, measured: np.ndarray) -> SeedCorrection:
    """Two levels, as seed 001 sec. 5.2 describes them: (1) a line x' = a x + b per twist component (N, 6);
    (2) the norms of the corrected translations and rotations get a second line fitted against the measured
    norms. The "fitted model" norm rows compare the uncorrected norms. Units are the caller's (mm, deg in
    the seed)."""
    x, y = np.asarray(model, dtype=float), np.asarray(measured, dtype=float)
    ft = fine_tune(x, y)
    xt = ft.apply(x)

    def norms(t):
        return np.column_stack([np.linalg.norm(t[:, :3], axis=1), np.linalg.norm(t[:, 3:], axis=1)])

    yn, xtn = norms(y), norms(xt)
    ftn = fine_tune(xtn, yn)
    return SeedCorrection(a=np.concatenate([ft.a, ftn.a]), b=np.concatenate([ft.b, ftn.b]),
                          fitted_error=np.column_stack([x - y, norms(x) - yn]),
                          tuned_error=np.column_stack([xt - y, ftn.apply(xtn) - yn]))
