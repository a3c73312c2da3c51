"""Stiffness-model fitting with a positive diagonal weight matrix, and linear fine-tuning (seed 001 sec. 3).

Fitting (seed 001 eqs. 10-12). The initial virtual-joint stiffness K_theta (from FEA / link tests) is scaled
by a diagonal matrix W with positive entries, ``K'_theta = W K_theta W^T`` (eq. 10; positive w keeps K'
positive definite). The entries of W are tied to few free weights by a map (eq. 12: 18 diagonal entries,
11 free weights, axial terms fixed to 1). The cost over m measurements (eq. 11)::

    E = sum e^T L e,    e = (sum_i K_i(W))^-1 F_exp - dX_exp

is minimized over log(w) (so w > 0) with a bounded trust-region least-squares solver from several starts
(start 0 at w = 1, the seed's choice; the others log-uniform in [0.1, 10]). As in the seed (Table 2), the
spread of each weight over the best runs tells which weights the data identify: a variance above a
threshold (0.1 in the seed) marks the weight as not identifiable from the data.

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


def scaled_stiffness(K_theta: np.ndarray, w: np.ndarray, weight_map) -> np.ndarray:
    """K' = W K W^T with W = diag(expand_weights(w)) (seed 001 eq. 10)."""
    d = expand_weights(w, weight_map)
    return d[:, None] * K_theta * d[None, :]


@dataclass(frozen=True)
class WeightFit:
    """Result of :func:`fit_weights`.

    ``weights`` (p,) best fit; ``cost`` its E; ``runs`` (r, p) weights of every start, ``run_costs`` (r,);
    ``top`` indices of the best runs used for the spread; ``variance`` (p,) of each weight over them;
    ``sensitivity`` (p,) norm of d(residual)/d(log w) at the best fit relative to the largest;
    ``unidentifiable`` (p,) bool: variance > threshold (seed 001 Table 2) or sensitivity < 1e-6 (a weight
    the data do not see at all, which a trust-region solver may leave anywhere).
    """

    weights: np.ndarray
    cost: float
    runs: np.ndarray
    run_costs: np.ndarray
    top: np.ndarray
    variance: np.ndarray
    sensitivity: np.ndarray
    unidentifiable: np.ndarray


def fit_weights(predict: Callable[[np.ndarray], np.ndarray], measured: np.ndarray, n_weights: int, *,
                error_weight=None, restarts: int = 8, top: int = 5, variance_threshold: float = 0.1,
                bounds=(1e-3, 1e3), seed: int = 0) -> WeightFit:
    """Fit positive weights w (n_weights,) so that ``predict(w)`` (N, 6) matches ``measured`` (N, 6) (seed 001 eq. 11).

    ``error_weight``: diagonal of L (6,) (default identity); ``restarts`` starts (the first at w = 1);
    the variance is taken over the ``top`` lowest-cost runs (seed 001: five).
    """
    from scipy.optimize import least_squares

    measured = np.asarray(measured, dtype=float)
    Lsqrt = np.sqrt(np.ones(measured.shape[1]) if error_weight is None else np.asarray(error_weight, dtype=float))
    lo, hi = np.log(bounds[0]), np.log(bounds[1])

    def residual(s):
        return ((predict(np.exp(s)) - measured) * Lsqrt).ravel()

    rng = np.random.default_rng(seed)
    starts = [np.zeros(n_weights)] + [rng.uniform(np.log(0.1), np.log(10.0), n_weights) for _ in range(restarts - 1)]
    runs, costs, jacs = [], [], []
    for s0 in starts:
        sol = least_squares(residual, s0, bounds=(lo, hi), method="trf", x_scale=1.0, xtol=1e-12, ftol=1e-14, gtol=1e-14,
                            max_nfev=200 * (n_weights + 1))
        runs.append(np.exp(sol.x))
        costs.append(2.0 * sol.cost)                     # E = sum e^T L e
        jacs.append(np.linalg.norm(sol.jac, axis=0))
        log.debug("start %d: E = %.4e after %d evaluations", len(runs), costs[-1], sol.nfev)
    runs, costs = np.array(runs), np.array(costs)
    order = np.argsort(costs)
    best = order[: max(1, min(top, len(order)))]
    var = np.var(runs[best], axis=0, ddof=1) if len(best) > 1 else np.zeros(n_weights)
    sens = jacs[order[0]] / max(float(np.max(jacs[order[0]])), np.finfo(float).tiny)
    return WeightFit(weights=runs[order[0]], cost=float(costs[order[0]]), runs=runs, run_costs=costs, top=best,
                     variance=var, sensitivity=sens, unidentifiable=(var > variance_threshold) | (sens < 1e-6))


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
