"""Where a located cause sits: which legs of an element type (issue 15 item 3), found without trying every subset.

For each element type e (an :class:`~femcheck.diagnose.effects._located.ElementInLegs` effect) the 2^6 - 1 leg
subsets are not fitted one by one. Instead (the screening of Chen & Chen's extended BIC, as in the serial-robot
diagnosis):

1. **Linearize** the readings in the six per-leg scales of e at the model as given: one batched model evaluation
   of all element types x legs x states, forward differences, G (N, 6) = d(prediction / sigma) / d leg_i;
2. **per-leg factors**: the weighted least-squares step b = argmin |r0 - G b|^2 on the residual of the model as
   given r0 = (measured - model) / sigma, with standard errors from s^2 (G^T G)^-1, s^2 = max(1, chi^2 / (N - k));
3. **backward elimination**: drop the leg with the smallest |t| = |b_i| / se_i, refit, until one leg is left; each
   subset L on that path (6, 5, ..., 1 legs) and the empty one is scored by its linearized extended BIC
   chi^2_lin(L) + |L| ln N + 2 ln C(6, |L|);
4. the subset with the lowest score is the placement of e (none if the empty one wins, or all six legs: that is the
   element's all-legs cause, e.g. ``actuation_compliance``, not a located one).

The placements of the element types with the lowest scores (at most ``keep``) then enter the diagnosis as
ordinary candidates: fitted with the full nonlinear model alone and in every pair, and weighed with their extended
BIC (:attr:`ElementInLegs.penalty`). Cost: one model evaluation of 30 x the readings, then 5 x 6 small least-squares
problems; the placements are chosen on the residual of the model as given (with another cause beside, the
located cause keeps that placement).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

#: forward-difference step of a leg's element scale (the model is smooth in it; the scales are O(1))
_STEP = 1e-3


@dataclasses.dataclass(frozen=True)
class Placement:
    """A screened placement: ``effect`` restricted to its legs, ``score`` its linearized extended BIC, ``score_none``
    the score of no change (chi^2 of the model as given), ``t`` the per-leg t-values of the full six-leg step."""

    effect: object
    score: float
    score_none: float
    t: tuple[float, ...]


def leg_jacobians(model, readings, located) -> np.ndarray:
    """(n_effects, N, 6) weighted Jacobian of every reading (N = 3 m, axes fastest) in the six per-leg scales of
    each effect of ``located``, at the model as given (one batched evaluation of len(located) x 6 x m states)."""
    m = len(readings.phase)
    base = np.array(np.broadcast_to(model.base_scale, (m, 6, 5)), float)
    d0 = model.tcp_displacement(readings.pose, readings.force, base)
    n = len(located)
    scale = np.broadcast_to(base, (n, 6, m, 6, 5)).copy()
    for a, eff in enumerate(located):
        for i in range(6):
            scale[a, i, :, i, eff.column] += _STEP
    d = model.tcp_displacement(np.tile(readings.pose, (n * 6, 1)), np.tile(readings.force, (n * 6, 1)),
                               scale.reshape(n * 6 * m, 6, 5))
    J = (d.reshape(n, 6, m, 3) - d0[None, None]) / _STEP / readings.sigma[None, None]
    return J.reshape(n, 6, 3 * m).transpose(0, 2, 1)


def _lstsq(G, r):
    """Least-squares step, chi^2 after it and the standard errors (s^2 inflated when the fit is worse than noise)."""
    b, *_ = np.linalg.lstsq(G, r, rcond=None)
    res = r - G @ b
    chi2 = float(res @ res)
    s2 = max(1.0, chi2 / max(len(r) - G.shape[1], 1))
    se = np.sqrt(np.clip(np.diag(s2 * np.linalg.pinv(G.T @ G)), 1e-300, None))
    return b, chi2, se


def screen_placements(model, readings, located, keep: int = 1) -> list[Placement]:
    """The best placement of each effect of ``located`` (see module doc), best first, at most ``keep`` of them, only
    those that beat no change. ``readings``: :class:`~femcheck.measured.Readings`."""
    if not located:
        return []
    r0 = ((readings.disp - model.tcp_displacement(readings.pose, readings.force,
                                                  np.array(np.broadcast_to(model.base_scale, (len(readings.phase), 6, 5))))
           ) / readings.sigma).ravel()
    N = r0.size
    chi2_0 = float(r0 @ r0)
    J = leg_jacobians(model, readings, located)
    out = []
    for eff, G in zip(located, J):
        legs = list(range(6))
        b, chi2, se = _lstsq(G, r0)
        t_full = tuple(float(x) for x in b / se)
        best_legs, best = (), chi2_0
        while legs:
            score = chi2 + len(legs) * math.log(N) + 2.0 * math.log(math.comb(6, len(legs)))
            if score < best:
                best_legs, best = tuple(legs), score
            if len(legs) == 1:
                break
            legs.pop(int(np.argmin(np.abs(b / se))))
            b, chi2, se = _lstsq(G[:, legs], r0)
        if best_legs and len(best_legs) < 6:   # all six legs is the element's all-legs cause, not a located one
            out.append(Placement(eff.restricted(best_legs), best, chi2_0, t_full))
    out.sort(key=lambda p: p.score)
    return out[:keep]
