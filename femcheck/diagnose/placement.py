"""Where a located cause sits: which legs of an element type, found without trying every subset.

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
4. the lowest score on that path, or that of the element changed alike in all legs (one factor: the six columns
   summed, chi^2_lin + ln N), ranks the element type (the empty subset scores chi^2 of the model as given). A
   lowest score at all six free legs is not taken as it is: with the prior's leg factors N(1, 1) a leg can be near
   rigid (0.03), far from the linearization at 1, and the six free legs then always fit the linear model best;
   step 5 decides;
5. for the ``keep`` (3) linearly best types that beat no change, whatever their distance to the best (a law that
   is piecewise in its scale, a thin pin bearing in its bores, is far from its linearization at 1 however well it
   fits), the legs are chosen again *nonlinearly*
   (a 2-3x softer element is far from the linearization at 1, and with all six legs free a uniform change of the
   element is nearly degenerate, so the backward path can end on the complement of the right legs): forward
   selection, adding the leg whose linearized step lowers chi^2 most at the current point, then three Gauss-Newton
   steps of the active legs (scales >= 0; one batched evaluation of 7 x m states each), scored by the extended BIC;
   up to all six legs (the element changed in every leg is a placement like the others, e.g. proximal-link tubes of
   a softer alloy: it is this element alone, where the whole-device ids move several elements at once), stopping
   after three steps that do not improve the score; then backward pruning of that subset (drop the leg whose removal
   lowers the score most, refit, while the score falls), since neighbouring legs' elements are alike and the forward
   path can take one too many.

Beside the leg set, each refined type is fitted changed alike in all six legs (5'.: one factor, Gauss-Newton on it,
scored chi^2 + ln N; :meth:`~femcheck.diagnose.effects._located.ElementInLegs.uniform_all`): a placement of its own,
so that an element changed in every leg (a softer tube alloy, thinner pins) is weighed with one parameter, like
the whole-device causes it competes with, and not with six. Not for the actuation, whose uniform change is the
vocabulary's ``actuation_compliance`` (the same law: two ids for it would split its mass).

The placements within ``margin`` of the best refined score (the diagnosis takes its ``max_located`` best; it refines
at least three types, since the linear ranking can put the wrong type first) then enter the diagnosis as ordinary
candidates:
fitted with the full nonlinear model alone and in every pair, and weighed with their extended BIC
(:attr:`ElementInLegs.penalty`). When two element types of the same legs are alike at the measured points (a
spherical and a universal joint sit next to each other), both enter and the evidence splits between them. Cost: one
model evaluation of 35 x the readings, 5 x 6 small least-squares problems, and 3 evaluations of 7 x the readings per
forward or pruning step of the refined types.

The screen linearizes about the model as given, or about a *background* (``background=(effects, values)``): other
causes held at their fitted values, e.g. the leading non-located single of a diagnosis. A located cause that is the
partner of a dominant cause in a pair is then placed on what that cause leaves, not on the dominant cause's own
residual (:func:`femcheck.diagnose.selection.located_partners`). The background is exact for the chain and every
effect of the vocabulary (:class:`_Background` applies the leg scales at the located effect's stage), but its
values are the background cause's fit *alone*, which the located cause has biased: an approximation, corrected by
the joint fit of the pair that follows.
"""
from __future__ import annotations

import dataclasses
import itertools
import logging
import math

import numpy as np

from femcheck.errors import ConvergenceError

log = logging.getLogger(__name__)

#: forward-difference step of a leg's element scale (the model is smooth in it; the scales are O(1))
_STEP = 1e-3


@dataclasses.dataclass(frozen=True)
class Placement:
    """A screened placement: ``effect`` restricted to its legs, ``score`` its extended BIC after the nonlinear leg
    selection (step 5), ``score_none`` the score of no change (chi^2 of the model as given), ``t`` the per-leg
    t-values of the linear six-leg step (step 2)."""

    effect: object
    score: float
    score_none: float
    t: tuple[float, ...]
    #: (k,) leg scales at the screen's optimum (the relinearized least squares on the background), a fit's start
    values: tuple[float, ...] | None = None


class _Background:
    """Predicted readings with the element scales of one element column set per leg, on top of ``effects`` (other,
    non-located causes) at their fitted ``values``: the model the screening linearizes. Without effects this is the
    model as given (one batched chain evaluation per call).

    The located effect *replaces* its column in the legs it holds (``ElementInLegs.apply``, stage 1), so the leg
    scales are applied where a fit of the pair would apply them: after the background effects of stage <= 1 (their
    column value is the leg's :meth:`neutral`, e.g. ``actuation_compliance``'s scale) and before those of later
    stages (``leg_softening`` multiplies, ``hertz_stiffening`` adds, the reading effects act on the result).
    Effects that change the force, the rotation compliance, the added displacement or the sensor do not depend on the
    leg scales, so a batch of n scale vectors is one chain evaluation of n x m states."""

    def __init__(self, model, readings, effects=(), values=(), stage: int = 1):
        from femcheck.diagnose.model import WorkingState
        self.model, self.readings = model, readings
        m = len(readings.phase)
        from femcheck.diagnose.extended_case import case_reading_effects
        order = sorted(case_reading_effects(model.case) + list(zip(effects, values)), key=lambda ev: ev[0].stage)
        st = WorkingState(force=np.array(readings.force, float),
                          scale=np.array(np.broadcast_to(model.base_scale, (m, 6, 5))), c_rot=0.0,
                          extra=np.zeros((m, 3)), sensor=np.eye(3))
        for eff, v in order:
            if eff.stage <= stage:
                eff.apply(model, readings, np.asarray(v, float), st)
        self._early = st
        self._late = [(eff, np.asarray(v, float)) for eff, v in order if eff.stage > stage]

    def neutral(self, column: int) -> np.ndarray:
        """(6,) leg scales of ``column`` that leave the background unchanged (the model's, or a stage-1 cause's)."""
        return np.array(self._early.scale[0, :, column], float)

    def __call__(self, column: int, X) -> np.ndarray:
        """(n, m, 3) predicted readings for leg scales ``X`` (n, 6) of element ``column``."""
        from femcheck.diagnose.model import WorkingState
        X = np.atleast_2d(np.asarray(X, float))
        n, m = len(X), len(self.readings.phase)
        scale = np.broadcast_to(self._early.scale, (n, m, 6, 5)).copy()
        scale[:, :, :, column] = X[:, None, :]
        extra, sensor, c_rot, force = self._early.extra, self._early.sensor, self._early.c_rot, self._early.force
        if self._late:
            outs = []
            for j in range(n):   # cheap array updates; the chain evaluation below stays one batched call
                st = WorkingState(force=force.copy(), scale=scale[j], c_rot=c_rot, extra=extra.copy(), sensor=sensor.copy())
                for eff, v in self._late:
                    eff.apply(self.model, self.readings, v, st)
                outs.append(st)
            force, c_rot, extra, sensor = outs[0].force, outs[0].c_rot, outs[0].extra, outs[0].sensor
            scale = np.stack([st.scale for st in outs])
        d = self.model.tcp_displacement(np.tile(self.readings.pose, (n, 1)), np.tile(force, (n, 1)),
                                        scale.reshape(n * m, 6, 5), c_rot)
        return (d.reshape(n, m, 3) + extra[None]) @ sensor.T


def leg_jacobians(model, readings, located, background: _Background | None = None) -> np.ndarray:
    """(n_effects, N, 6) weighted Jacobian of every reading (N = 3 m, axes fastest) in the six per-leg scales of
    each effect of ``located``, at the model as given or at ``background`` (one batched evaluation of
    len(located) x 6 x m states per element column)."""
    bg = background or _Background(model, readings)
    out = []
    for eff in located:
        x0 = bg.neutral(eff.column)
        X = np.vstack([x0, x0 + _STEP * np.eye(6)])
        d = bg(eff.column, X)
        out.append(((d[1:] - d[0][None]) / _STEP / readings.sigma[None]).reshape(6, -1).T)
    return np.array(out)


def _lstsq(G, r):
    """Least-squares step, chi^2 after it and the standard errors (s^2 inflated when the fit is worse than noise)."""
    b, *_ = np.linalg.lstsq(G, r, rcond=None)
    res = r - G @ b
    chi2 = float(res @ res)
    s2 = max(1.0, chi2 / max(len(r) - G.shape[1], 1))
    se = np.sqrt(np.clip(np.diag(s2 * np.linalg.pinv(G.T @ G)), 1e-300, None))
    return b, chi2, se


def _state(bg: _Background, eff, x):
    """Weighted residual r (N,) at leg scales ``x`` (6,) of ``eff`` over the background ``bg`` and its Jacobian
    G (N, 6) in the six scales (one batched evaluation of 7 x m states, forward differences)."""
    d = bg(eff.column, np.vstack([x, x + _STEP * np.eye(6)]))
    readings = bg.readings
    r = ((readings.disp - d[0]) / readings.sigma).ravel()
    G = ((d[1:] - d[0][None]) / _STEP / readings.sigma[None]).reshape(6, -1).T
    return r, G


def _upper(eff) -> float:
    """The largest leg scale a fit of ``eff`` may take (its parameters' upper bound): a Gauss-Newton step of the screen
    stays where the fit can follow, and the chain is never asked for an element thousands of times softer."""
    return float(eff.params[0].upper)


def _forward(bg: _Background, eff, score_none, ebic, iters: int = 3):
    """Forward selection of legs with relinearization (see module doc, step 5): ((score, legs), leg scales (6,)) of
    the best subset."""
    x0 = bg.neutral(eff.column)
    x = x0.copy()
    r, G = _state(bg, eff, x)
    active, best, worse, best_x = [], (score_none, ()), 0, x.copy()
    while len(active) < 6 and worse < 3:
        trial = []
        for leg in set(range(6)) - set(active):
            cols = active + [leg]
            _, chi2, _ = _lstsq(G[:, cols], r)
            trial.append((chi2, leg))
        active.append(min(trial)[1])
        for _ in range(iters):   # Gauss-Newton on the active legs, the others at the model's value
            b, _, _ = _lstsq(G[:, active], r)
            x[active] = np.clip(x[active] + b, 0.0, _upper(eff))
            r, G = _state(bg, eff, x)
        score = ebic(float(r @ r), len(active))
        worse = worse + 1 if score >= best[0] else 0
        if score < best[0]:
            best, best_x = (score, tuple(sorted(active))), x.copy()
    while len(best[1]) > 1:   # backward pruning: neighbouring legs' elements are alike, forward may pick one too many
        trials = []
        for leg in best[1]:
            keep = [i for i in best[1] if i != leg]
            x = best_x.copy()
            x[leg] = x0[leg]
            for _ in range(iters):
                r, G = _state(bg, eff, x)
                b, _, _ = _lstsq(G[:, keep], r)
                x[keep] = np.clip(x[keep] + b, 0.0, _upper(eff))
            r, _ = _state(bg, eff, x)
            trials.append((ebic(float(r @ r), len(keep)), tuple(keep), x))
        score, legs, x = min(trials, key=lambda t: t[0])
        if score >= best[0]:
            break
        best, best_x = (score, legs), x
    return best, best_x


def _uniform(bg: _Background, eff, iters: int = 6) -> tuple[float, float]:
    """(chi^2, factor) of the element ``eff`` changed alike in all six legs (one factor, ``ElementInLegs.uniform_all``):
    Gauss-Newton on the common factor from the background's value (one batched evaluation of 2 x m states each)."""
    readings = bg.readings
    a = float(bg.neutral(eff.column).mean())
    for _ in range(iters + 1):
        d = bg(eff.column, np.array([np.full(6, a), np.full(6, a + _STEP)]))
        r = ((readings.disp - d[0]) / readings.sigma).ravel()
        if _ == iters:
            break
        g = ((d[1] - d[0]) / _STEP / readings.sigma).ravel()
        a = min(max(a + float(g @ r) / max(float(g @ g), 1e-300), 0.0), _upper(eff))
    return float(r @ r), a


def screen_placements(model, readings, located, keep: int = 3, margin: float = 10.0,
                      background=None) -> list[Placement]:
    """The best placement of each effect of ``located`` (see module doc), best first: those within ``margin`` of the
    best score (at most ``keep``), only those that beat no change. ``readings``: :class:`~femcheck.measured.Readings`.

    ``background``: (effects, values) of other causes held at their fitted values (e.g. the leading non-located
    single of a diagnosis): the placement is then chosen on what that cause leaves, the partner of a pair, instead of
    on the residual of the model as given (``score_none`` is then the chi^2 of the background alone)."""
    if not located:
        return []
    bg = _Background(model, readings, *(background or ((), ())))
    r0 = ((readings.disp - bg(located[0].column, bg.neutral(located[0].column))[0]) / readings.sigma).ravel()
    N = r0.size
    chi2_0 = float(r0 @ r0)
    ebic = lambda chi2, k: chi2 + k * math.log(N) + (2.0 * math.log(math.comb(6, k)) if k < 6 else 0.0)
    J = leg_jacobians(model, readings, located, bg)
    linear = []
    for eff, G in zip(located, J):   # 1.-4. linearized backward elimination: ranks the element types
        legs = list(range(6))
        b, chi2, se = _lstsq(G, r0)
        t_full = tuple(float(x) for x in b / se)
        # the element changed alike in all legs: one parameter, the sum of the six legs' columns
        _, chi2_u, _ = _lstsq(G.sum(axis=1, keepdims=True), r0)
        best = min((chi2_0, ()), (chi2_u + math.log(N), tuple(range(6))))
        while legs:
            best = min(best, (ebic(chi2, len(legs)), tuple(legs)))
            if len(legs) == 1:
                break
            legs.pop(int(np.argmin(np.abs(b / se))))
            b, chi2, se = _lstsq(G[:, legs], r0)
        linear.append((best[0], eff, t_full, len(best[1])))
    linear.sort(key=lambda t: t[0])
    out = []
    for score_lin, eff, t_full, _n_legs in linear[:keep]:
        # the linear score ranks, the refinement decides: a law that is nonlinear in its scale (a thin pin stiffening
        # as it bears on the opposite line of its bore) is far from its linearization at 1 however well it fits
        if score_lin >= chi2_0:
            break
        # a linear minimum at all six legs is not taken as it is: a leg scale far from 1 (a near-rigid element,
        # 0.03) is far outside the linearization at 1, where six free legs always fit best. The nonlinear forward
        # selection decides, up to all six legs
        try:
            (score, legs), x = _forward(bg, eff, chi2_0, ebic)   # 5. the legs, nonlinear
        except ConvergenceError as exc:   # the chain has no state at those scales: not a placement this type can take
            log.info("placement of %s not refined: %s", eff.id, exc)
            continue
        if legs:
            out.append(Placement(eff.restricted(legs), score, chi2_0, t_full, tuple(float(x[i]) for i in legs)))
        if eff.uniform_cause is not None:   # e.g. actuation_compliance: that cause weighs the uniform change
            continue
        try:
            chi2_u, a = _uniform(bg, eff)   # 5'. all legs, one factor: weighed beside the leg set (its own placement)
        except ConvergenceError as exc:
            log.info("uniform placement of %s not refined: %s", eff.id, exc)
            continue
        if chi2_u + math.log(N) < chi2_0:
            out.append(Placement(eff.uniform_all(), chi2_u + math.log(N), chi2_0, t_full, (a,)))
    out.sort(key=lambda p: p.score)
    return [p for p in out if p.score <= out[0].score + margin] if out else []


#: placements whose linearized score is within this of the best get the chain's chi^2 at their step
#: (:func:`subset_scores`); 20 = a posterior weight of e^-10 relative to the best
NONLINEAR_MARGIN = 20.0

#: largest leg-scale step (in the scale's units) whose linearized chi^2 is taken as it is (:func:`subset_scores`):
#: the chain's response to a compliance scale is smooth, its second-order term ~ step^2 / 2 of the first
LINEAR_STEP = 0.25

#: every placement a located cause can take: the non-empty leg subsets, all six legs included, grouped by size
SUBSETS_BY_SIZE = {k: np.array(list(itertools.combinations(range(6), k)), int) for k in range(1, 7)}


def subset_scores(G: np.ndarray, r0: np.ndarray, sd: np.ndarray, log_mass: np.ndarray, n_data: int,
                  sigma_dof: int = 0, lower: np.ndarray | None = None, chi2_at=None,
                  chain_below: float = np.inf) -> tuple[list, dict]:
    """-2 ln evidence of every placement of one element type, each linearized about the same point.

    ``G`` (N, 6): weighted Jacobian of the readings in the six leg scales; ``r0`` (N,): weighted residual at the
    linearization point; ``sd`` (6,) the prior width of each leg's scale deviation (prior N(0, sd^2) about that
    point, :mod:`femcheck.diagnose.prior`), ``log_mass`` (6,) ln of its mass inside the bounds. For the legs L
    (k of them), with A = G_L^T G_L, c = G_L^T r0, P = diag(sd_L^-2), W = diag(sd_L):

    * chi^2_L at the maximum a posteriori step x = (A + P)^-1 c (not the least-squares one: for an element the
      readings barely see, least squares asks for a non-physical factor, 20x or negative, that no fit within the
      bounds and no truth of the prior reaches); BIC score chi^2_L + k ln N + 2 ln C(6, k);
    * Laplace (exact for the linear model with a Gaussian prior: r0 ~ N(0, I + G_L W^2 G_L^T)):
      r0^T r0 - c^T (A + P)^-1 c + ln det(I + W A W) + 2 sum ln mass + 2 ln C(6, k);
    * Student-t likelihood (``sigma_dof`` > 0): :func:`~femcheck.diagnose.evidence.student_term` of chi^2_L in
      place of chi^2_L, the Gaussian Occam terms kept (their curvature scaling is left out).

    ``lower`` (6,): the smallest step of each leg's scale (a compliance scale >= 0: minus the linearization point).
    A MAP step below it (a negative compliance, which the linear model happily fits and the chain cannot have) is
    replaced by the bounded one (bounded-variable least squares on [G_L; P^1/2] x = [r0; 0]); the Occam term is
    then still the Gaussian one (the posterior cut by the bound is not integrated: an approximation).

    ``chi2_at``: a function of the steps X (n, 6) returning the chi^2 of the full model there (n,). Given, chi^2_L is
    that of the model at the MAP step, not the linear model's, and the prior penalty is added to it for Laplace: the
    linear model is exact for a small change and can promise a much better fit than the chain gives for a large one
    (a guideway 3x softer in five legs, linear chi^2 119 against 186 at the same step). Only the placements within
    :data:`NONLINEAR_MARGIN` of the best score are evaluated (one batched call per round, rounds until the best no
    longer moves), and only those whose step exceeds :data:`LINEAR_STEP` in some leg; the others keep the linear
    chi^2. Not at all when even the best linearized score is above
    ``chain_below`` (an element type hopeless against the rivals already weighed: its mass is negligible whatever
    the correction; the linear score is exact for the small steps where a type is close, and a large change is
    fitted by the screen).

    Returns (subsets, scores): the (n_subsets,) leg tuples (1..6 legs, in :data:`SUBSETS_BY_SIZE` order) and
    {(method, likelihood): (n_subsets,) scores, "chi2": (n_subsets,) chi^2_L}. One batched solve per subset size."""
    from scipy.optimize import lsq_linear

    from femcheck.diagnose.evidence import student_term
    A = G.T @ G
    c = G.T @ r0
    chi0 = float(r0 @ r0)
    ln_n = math.log(max(n_data, 1))
    subsets, chi, bic_extra, occam, steps, prior_pen = [], [], [], [], [], []
    for k, S in SUBSETS_BY_SIZE.items():
        AL = A[S[:, :, None], S[:, None, :]]                       # (n, k, k)
        cL = c[S][..., None]                                        # (n, k, 1)
        w = sd[S]                                                   # (n, k)
        x_map = np.linalg.solve(AL + np.eye(k) / w[:, :, None] ** 2, cL)                          # (n, k, 1)
        quad = chi0 - (cL * x_map).sum(axis=(1, 2))          # chi^2 + prior penalty at the MAP point
        if lower is not None:
            for i in np.flatnonzero((x_map[..., 0] < lower[S]).any(axis=1)):   # the few placements that hit a bound
                L = list(S[i])
                M = np.vstack([G[:, L], np.diag(1.0 / sd[L])])
                x = lsq_linear(M, np.concatenate([r0, np.zeros(k)]), bounds=(lower[L], np.inf), method="bvls").x
                x_map[i, :, 0] = x
                quad[i] = float(np.sum((M @ x - np.concatenate([r0, np.zeros(k)])) ** 2))
        # chi^2 at the MAP point: the least-squares step of a weakly seen element can be a non-physical factor
        # (20x, or negative) that the prior rules out; the MAP step stays within what the prior allows
        chi_k = np.maximum(chi0 - 2.0 * (cL * x_map).sum(axis=(1, 2)) + (x_map * (AL @ x_map)).sum(axis=(1, 2)), 0.0)
        logdet = np.linalg.slogdet(np.eye(k) + w[:, :, None] * AL * w[:, None, :])[1]
        pen = 2.0 * math.log(math.comb(6, k))
        subsets.extend(tuple(int(i) for i in row) for row in S)
        X = np.zeros((len(S), 6))
        np.put_along_axis(X, S, x_map[..., 0], axis=1)
        steps.append(X)
        prior_pen.append(((x_map[..., 0] / w) ** 2).sum(axis=1))
        chi.append(chi_k)
        bic_extra.append(np.full(len(S), k * ln_n + pen))
        occam.append(quad - chi_k + logdet + 2.0 * log_mass[S].sum(axis=1) + pen)   # quad - chi_k: the prior penalty
    chi, bic_extra, occam = (np.concatenate(v) for v in (chi, bic_extra, occam))
    if chi2_at is not None and float(np.min(chi + np.minimum(bic_extra, occam))) <= chain_below:
        # the chain only where it can matter: the placements within NONLINEAR_MARGIN of the best score so far (a
        # placement further off weighs < e^-10 of it); repeated while a correction moves the best (the linear
        # model can be optimistic, and a placement that looked worse may then lead)
        steps = np.vstack(steps)
        # a small step is where the linear model is exact to second order: those keep the linear chi^2
        done = np.abs(steps).max(axis=1) <= LINEAR_STEP
        while True:
            score = chi + np.minimum(bic_extra, occam)
            todo = ~done & (score <= score.min() + NONLINEAR_MARGIN)
            if not todo.any():
                break
            chi[todo] = np.asarray(chi2_at(steps[todo]), float)   # the Occam parts stay
            done |= todo
    out = {}
    for lik in ("gauss", "student"):
        term = student_term(chi, n_data, sigma_dof) if lik == "student" and sigma_dof > 0 else chi
        out[("bic", lik)] = term + bic_extra
        out[("laplace", lik)] = term + occam
    out["chi2"] = chi
    return subsets, out


def unweighed_placements(model, readings, located, *, skip=None, background=None, base_scores=None,
                         sigma_dof: int = 0, hopeless_above: float = np.inf) -> list[tuple[object, dict]]:
    """The evidence of each located cause summed over the placements that no fit weighed.

    A diagnosis fits a few placements of each element type (the screen's best, the partners, ...). The posterior of
    an element type is the sum over *all* its placements, -2 ln sum_L exp(-s_L / 2); the others are scored here
    with :func:`subset_scores`, linearized about the model as given or about ``background`` (effects, values: the
    lead cause of a pair, held at its fitted values). Without this a located cause below the detection limit (never
    placed, since no placement beats none) got probability 0, where its prior, discounted by its Occam factor, is
    what the data support: on 120 prior-drawn calibration sets the located causes given < 0.1 were right 3.4 % of the
    time against 0.2 % predicted (docs/diagnose.md). The linearization is exact for a small change (where it
    matters: the weighed placements carry the large ones) and underrates a large one, which a fit would place.

    ``skip``: {effect id: set of leg tuples already weighed}; ``base_scores``: {(method, likelihood): -2 ln evidence
    of the background cause minus its chi^2} (its Occam and penalty terms), added for a pair; the residual of the
    background replaces the model's. ``hopeless_above``: a -2 ln evidence (with the background's terms) beyond which
    an element type's placements are not evaluated on the chain (:func:`subset_scores` ``chain_below``). Returns
    [(effect, {(method, likelihood): score}, best legs, their chi^2)] for every element type that has unweighed
    placements (the best by the Gaussian BIC, for the report)."""
    from scipy.special import logsumexp

    from femcheck.diagnose.prior import effect_prior
    bg = _Background(model, readings, *(background or ((), ())))
    J = leg_jacobians(model, readings, located, bg)
    n_data = 3 * readings.n_states
    out = []
    # the background's own prediction: the same for every element column at its neutral scales
    r0 = ((readings.disp - bg(located[0].column, bg.neutral(located[0].column))[0]) / readings.sigma).ravel()
    for eff, G in zip(located, J):
        q = effect_prior(eff.restricted(range(6)), model)
        x0 = bg.neutral(eff.column)
        lower = np.array([p.lower for p in eff.restricted(range(6)).params]) - x0

        def chi2_at(X, eff=eff, x0=x0, lower=lower):
            d = bg(eff.column, x0[None] + np.clip(X, lower, None))
            return (((readings.disp[None] - d) / readings.sigma[None]) ** 2).sum(axis=(1, 2))

        base = min((base_scores or {}).get(("bic", "gauss"), 0.0), (base_scores or {}).get(("laplace", "gauss"), 0.0))
        subsets, scores = subset_scores(G, r0, q.sd, np.log(np.clip(q.mass, 1e-300, 1.0)), n_data, sigma_dof,
                                        lower=lower, chi2_at=chi2_at, chain_below=hopeless_above - base)
        done = (skip or {}).get(eff.id, set())
        keep = np.array([s not in done for s in subsets])
        if not keep.any():
            continue
        chi = scores.pop("chi2")
        total = {key: float(-2.0 * logsumexp(-0.5 * v[keep])) + (base_scores or {}).get(key, 0.0)
                 for key, v in scores.items()}
        best = int(np.argmin(np.where(keep, scores[("bic", "gauss")], np.inf)))
        out.append((eff, total, subsets[best], float(chi[best])))
    return out
