"""Model selection that does not fool itself.

Greedy forward selection over the effect library, at most ``max_effects`` (2) effects:

1. every applicable effect not yet in the model is fitted jointly with the effects already chosen
   (:func:`femcheck.diagnose.fitting.fit_effects`) and ranked by the Bayesian information criterion
   BIC = chi^2 + k ln N (Schwarz 1978); only candidates improving BIC by more than ``bic_margin`` (10,
   "very strong" evidence on Kass & Raftery's scale) go on;
2. the ``shortlist`` best are cross-validated by leaving test points out (``n_folds`` folds of points;
   sweep readings belong to P0): fitted without the held-out points, they predict the held-out readings;
3. the candidate with the lowest held-out chi^2 is accepted only if it lowers the held-out chi^2 of the
   current model by more than measurement noise explains, ``2 sqrt(2 N_heldout)`` (twice the standard
   deviation of a chi^2 with N_heldout degrees of freedom). A single step need not lower the relative
   deflection error (friction alone, for instance, fits the preload and unload readings but not eq. 1's
   deflection when a stiffness error hides beside it);
4. the final model must lower the held-out mean relative error of the deflection below the model as given.

If no effect is accepted in the first round, or step 4 fails, the answer is ``none``. The held-out errors reported are
those of the cross-validation: ``heldout_error_before`` of the model as given (no parameters fitted, so
its held-out and in-sample errors coincide), ``heldout_error_after`` of the selected extension.
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np

from femcheck.diagnose import evidence, residuals
from femcheck.diagnose.lack_of_fit import structured_lack_of_fit
from femcheck.diagnose.effects import effects as effect_registry
from femcheck.diagnose.fitting import FitResult, fit_effects
from femcheck.diagnose.placement import Placement, screen_placements, unweighed_placements

log = logging.getLogger(__name__)

EVIDENCE_TEXT = {
    "bic": "BIC (Schwarz): -2 ln p(D|M) ~ chi2 + k ln N; prior: equal mass per explanation size (none, singles, pairs), "
           "shared within the size",
    "laplace": "Laplace: -2 ln p(D|M) ~ chi2 + d'(P - P(A+P)^-1 P)d + ln det(I + W A W) + 2 sum ln mass (A = J'J, "
               "parameter prior N(mu, W^2) of femcheck.diagnose.prior); prior: equal mass per explanation size (none, "
               "singles, pairs), shared within the size"}
LIKELIHOOD_TEXT = {
    "gauss": "Gaussian, sigma known: -2 ln L = chi2",
    "student": "Student-t, sigma^2 integrated out of its scatter estimate with nu dof: -2 ln L = (N + nu) ln(1 + chi2/nu) "
               "(Gaussian limit when nu = 0: sigma from the dial quantum or stated)"}
#: |trial drift| / its standard error above which the readings drift with trial order (a finding)
DRIFT_Z = 5.0


@dataclasses.dataclass(frozen=True)
class CrossValidation:
    """Held-out predictions: ``delta`` (c, 3) m eq. 1 deflections, ``states`` (m, 3) readings, ``chi2`` over all
    held-out states, ``error`` / ``error_along`` {axis: mean relative error, 'overall'}."""

    delta: np.ndarray
    states: np.ndarray
    chi2: float
    error: dict
    error_along: dict


@dataclasses.dataclass(frozen=True)
class Cause:
    id: str
    location: str
    params: dict
    params_ci: dict

    probability: float = 1.0
    on_bound: tuple[str, ...] = ()
    #: for a located cause (``<element>_in_legs``): the element type and the legs it sits in
    element: str = ""
    legs: tuple[int, ...] = ()
    #: importance: the held-out mean relative deflection error (percentage points) that leaving this cause out of the
    #: named explanation adds (:func:`heldout_losses`); 0 for ``none``
    heldout_loss_pct: float = 0.0

    def as_dict(self) -> dict:
        out = {"id": self.id, "probability": self.probability, "location": self.location, "params": self.params,
               "params_ci": self.params_ci, "on_bound": list(self.on_bound), "heldout_loss_pct": self.heldout_loss_pct}
        if self.element:
            out.update(element=self.element, legs=list(self.legs))
        return out


@dataclasses.dataclass(frozen=True)
class Diagnosis:
    """Result of :func:`diagnose` (see module docstring). ``steps``: per round, the candidates with their BIC,
    held-out chi^2 / error and whether accepted; ``baseline``: seed 001 weight fit held-out errors."""

    model_name: str
    causes: tuple[Cause, ...]
    significant: bool
    base: FitResult
    fit: FitResult
    cv_before: CrossValidation
    cv_after: CrossValidation
    steps: tuple[dict, ...]
    folds: tuple[tuple[str, ...], ...]
    warnings: tuple[str, ...]
    noise_threshold: float
    baseline_error: dict | None = None
    readings: object = dataclasses.field(default=None, repr=False)
    weighing: object = dataclasses.field(default=None, repr=False)
    #: screened placements of the located effects that joined the candidates (``femcheck.diagnose.placement``)
    placements: tuple = ()
    #: structured lack of fit of the named explanation (``femcheck.diagnose.lack_of_fit.LackOfFit``)
    lack_of_fit: object = None
    #: further placements weighed alone and in pairs with the leading non-located singles (:func:`located_partners`)
    partner_placements: tuple = ()
    #: named causes whose parameters the data cannot tell apart: (id, id, correlation) (:func:`collinear_causes`)
    collinear: tuple = ()
    #: where sigma came from when no trial repeats (:func:`sigma_from_richest_rival`); "" when from the trials
    sigma_note: str = ""
    #: :func:`clearance_needed` when the search named a clearance (None otherwise)
    clearance_check: dict | None = None
    #: named causes the readings cannot separate from other element types on the same legs (:func:`alias_groups`)
    alias_groups: tuple = ()

    @property
    def verdict(self) -> str:
        return self.weighing.verdict

    def residual_json(self) -> dict:
        """Goodness of fit of the leading explanation and where its residual sits (chi^2 share per point,
        per signed direction, and per phase of the load sweep)."""
        w, r = self.weighing, self.readings
        z2 = (((self.fit.predicted - r.disp) / r.sigma) ** 2).sum(axis=1)
        tot = max(float(z2.sum()), 1e-300)
        share = lambda keys: {str(k): float(z2[keys == k].sum() / tot) for k in dict.fromkeys(keys.tolist())}
        return {"chi2_per_dof": w.chi2_per_dof, "p_value": w.p_value, "sigma_m": float(r.reading_sigma_m),
                "sigma_estimated": True, "sigma_source": sigma_source(r, self.sigma_note),
                "unexplained_fraction": w.unexplained_fraction, "chi2": float(self.fit.chi2), "n_data": w.n_data,
                "n_params": int(self.fit.n_params), "chi2_per_dof_none": w.chi2_per_dof_none,
                "p_value_none": w.p_value_none, "chi2_share_by_point": share(np.asarray(r.point)),
                "chi2_share_by_direction": share(np.asarray(r.direction)),
                "chi2_share_by_phase": share(np.asarray(r.phase)),
                "trial_drift_m_per_trial": float(r.trial_drift_m), "trial_drift_z": self.drift_z,
                "reading_quantum_m": float(r.quantum_m), "shape": self.residual_shape(),
                **(self.lack_of_fit.as_dict() if self.lack_of_fit is not None else {})}

    def residual_shape(self) -> dict:
        """What the remaining residual looks like. Along each loaded state's force direction u the residual
        a = u.(measured - model) is fitted, weighted by sigma, as a = alpha |F| + beta: ``load_proportional``
        when alpha / se(alpha) > 3, ``load_independent`` when beta / se(beta) > 3; ``hysteretic`` when the unload
        readings' residual differs from the loading ones at the same load by > 3 standard errors;
        ``drifting`` when the readings drift with trial order (|z| > DRIFT_Z). ``shape`` lists those that hold."""
        r = self.readings
        f = np.linalg.norm(r.force, axis=1)
        ok = f > 0
        u = r.force[ok] / f[ok, None]
        a = np.einsum("ij,ij->i", r.disp[ok] - self.fit.predicted[ok], u)
        sd = r.sigma[ok, 0]
        A = np.column_stack([f[ok], np.ones(ok.sum())]) / sd[:, None]
        out = {"load_proportional_z": 0.0, "load_independent_z": 0.0, "hysteresis_z": 0.0}
        if ok.sum() >= 3:
            coef, *_ = np.linalg.lstsq(A, a / sd, rcond=None)
            cov = np.linalg.pinv(A.T @ A)
            se = np.sqrt(np.clip(np.diag(cov), 1e-300, None))
            out["load_proportional_z"], out["load_independent_z"] = float(coef[0] / se[0]), float(coef[1] / se[1])
            out["load_proportional_m_per_N"], out["load_independent_m"] = float(coef[0]), float(coef[1])
        unl = np.flatnonzero((r.phase == "unload") & (r.case_index >= 0) & (f > 0))
        if unl.size:
            pre = r.preload_state[r.case_index[unl]]
            uu = r.force[unl] / f[unl, None]
            h = np.einsum("ij,ij->i", (r.disp[unl] - self.fit.predicted[unl]) - (r.disp[pre] - self.fit.predicted[pre]), uu)
            se_h = np.sqrt(r.sigma[unl, 0] ** 2 + r.sigma[pre, 0] ** 2)
            out["hysteresis_z"] = float(h.mean() / (np.sqrt(np.sum(se_h ** 2)) / h.size))
        shape = [n for n, k in (("load_proportional", "load_proportional_z"), ("load_independent", "load_independent_z"),
                                ("hysteretic", "hysteresis_z")) if abs(out[k]) > 3.0]
        if abs(self.drift_z) > DRIFT_Z:
            shape.append("drifting_with_trial_order")
        out["shape"] = shape or ["noise"]
        return out

    @property
    def drift_z(self) -> float:
        r = self.readings
        return float(r.trial_drift_m / r.trial_drift_sigma_m) if r.trial_drift_sigma_m > 0 else 0.0

    @property
    def heldout_error_before(self) -> dict:
        return self.cv_before.error

    @property
    def heldout_error_after(self) -> dict:
        return self.cv_after.error

    def _by_direction(self, cv) -> dict:
        return residuals.mean_by_direction(self.readings, residuals.case_errors(self.readings, cv.delta)["vector"])

    def as_json(self) -> dict:
        w = self.weighing
        return {"model": self.model_name, "verdict": w.verdict, "rank_by": "heldout_loss",
                "causes": [c.as_dict() for c in self.causes], "collinear": [list(c) for c in self.collinear],
                "alternatives": w.alternatives(), "ambiguous": w.ambiguous, "ambiguity": w.ambiguity,
                "evidence": EVIDENCE_TEXT[w.method],
                "likelihood": LIKELIHOOD_TEXT[w.likelihood], "sigma_dof": int(w.sigma_dof),
                "residual": self.residual_json(),
                "heldout_error_before": self.cv_before.error, "heldout_error_after": self.cv_after.error,
                "heldout_error_along_load_before": self.cv_before.error_along,
                "heldout_error_along_load_after": self.cv_after.error_along,
                "heldout_error_by_direction_before": self._by_direction(self.cv_before),
                "heldout_error_by_direction_after": self._by_direction(self.cv_after),
                "significant": self.significant,
                "heldout_chi2_before": self.cv_before.chi2, "heldout_chi2_after": self.cv_after.chi2,
                "noise_threshold_chi2": self.noise_threshold,
                "baseline_weight_fit_heldout_error": self.baseline_error,
                "folds": [list(f) for f in self.folds], "warnings": list(self.warnings),
                "clearance_check": self.clearance_check, "alias_groups": list(self.alias_groups),
                "steps": list(self.steps),
                "placements": [{"id": p.effect.id, "legs": list(p.effect.legs), "screen_ebic": p.score,
                                "screen_ebic_none": p.score_none, "t_per_leg": list(p.t), "one_factor": p.effect.uniform}
                               for p in self.placements],
                "partner_placements": [{"id": p.effect.id, "legs": list(p.effect.legs), "screen_ebic": p.score,
                                        "screen_ebic_none": p.score_none, "one_factor": p.effect.uniform}
                                       for p in self.partner_placements]}


def sigma_source(readings, rival_note: str = "") -> str:
    """Where the reading sigma comes from, in words: never from an explanation being judged
    (:mod:`femcheck.measured.protocol`; ``rival_note``: :func:`sigma_from_richest_rival`'s, for single-trial data)."""
    if rival_note:
        return rival_note
    if readings.sigma_dof > 0:
        return f"estimate: spread of the repeated trials ({readings.sigma_dof} dof)"
    return (f"estimate: dial step {readings.quantum_m * 1e6:.3g} um / sqrt(12), the readings repeating exactly "
            f"(a floor: the scatter is below the step)")


def sigma_from_richest_rival(model, readings, pool, folds):
    """Readings with sigma estimated where no trial repeats (one reading per state: no scatter to pool, only the dial
    step's floor): from the held-out residual of the most flexible rival, every non-located effect of ``pool`` fitted
    jointly (k parameters), which no explanation being weighed can beat by much and none of them is judged by.

    Leave-points-out residuals of a least-squares fit overstate the noise by the leverage, E r_ho,i^2 = sigma^2 /
    (1 - h_ii), ~ sigma^2 N / (N - k) on average, so ``sigma^2 = RSS_ho (N - k) / N^2`` with N - k degrees of freedom.
    A uniform sigma does not change a least-squares fit, so the rival is fitted once at the readings' floor sigma
    and the estimate set before any explanation is searched. Returns (readings, note); the readings unchanged (and
    note "") when trials repeat or the rival cannot be fitted."""
    if readings.n_trials.max() > 1 or not pool:
        return readings, ""
    rich = fit_effects(model, readings, list(pool))
    cv = cross_validate(model, readings, list(pool), rich, folds)
    n = 3 * readings.n_states
    k = int(rich.n_params)
    if n - k < 3:
        return readings, ""
    rss = float(np.sum(((cv.states - readings.disp) / readings.sigma) ** 2))   # in units of the floor sigma
    scale = float(np.sqrt(rss * (n - k) / n ** 2))
    if not scale > 1.0:   # never below the dial step's floor
        return readings, ""
    out = dataclasses.replace(readings, sigma=readings.sigma * scale, delta_sigma=readings.delta_sigma * scale,
                              reading_sigma_m=readings.reading_sigma_m * scale, sigma_dof=n - k)
    note = (f"estimate: held-out residual of the most flexible rival ({'+'.join(rich.ids)}, {k} parameters; "
            f"{n - k} dof), no repeated trials")
    log.info("single trial: sigma %.3g m from %s", out.reading_sigma_m, note)
    return out, note


def point_folds(readings, n_folds: int = 3) -> tuple[tuple[str, ...], ...]:
    """Leave-points-out folds: the points (sorted by label) dealt round-robin into ``n_folds`` groups."""
    pts = sorted(readings.points, key=lambda p: (len(p), p))
    n = max(2, min(n_folds, len(pts)))
    return tuple(tuple(pts[j::n]) for j in range(n))


def cross_validate(model, readings, effects, full: FitResult, folds) -> CrossValidation:
    """Fit without each fold's points (warm start at the full fit) and predict the held-out readings."""
    states = full.predicted.copy()
    if full.n_params:
        start = [np.concatenate(full.values)]
        for fold in folds:
            test = np.isin(readings.point, fold)
            f = fit_effects(model, readings, effects, mask=~test, starts=start, max_nfev=100)
            states[test] = f.predicted[test]
    chi2 = float(np.sum(((states - readings.disp) / readings.sigma) ** 2))
    delta = residuals.case_deltas(readings, states)
    err = residuals.case_errors(readings, delta)
    return CrossValidation(delta=delta, states=states, chi2=chi2, error=residuals.mean_by_axis(readings, err["vector"]),
                           error_along=residuals.mean_by_axis(readings, err["along"]))


def _lack_of_fit(readings, f: FitResult):
    return structured_lack_of_fit(readings, f.predicted, jacobian=f.jacobian, n_params=f.n_params,
                                  sigma_dof=readings.sigma_dof, kind="both")


def _explanation(f: FitResult) -> evidence.Explanation:
    return evidence.Explanation(f.ids, f.chi2, f.n_params, f, penalty=f.penalty,
                                occam=f.occam if f.occam is not None else (0.0 if f.n_params == 0 else None),
                                occam_student=f.occam_student)


#: a rival pair whose chi^2 cannot come within this of the leader's -2 ln (prior x evidence) is not fitted to the end
#: (posterior < exp(-HOPELESS / 2) = 2e-9 of the leader's, under either evidence approximation and either likelihood)
HOPELESS = 40.0


def _total(ex: evidence.Explanation, n_data: int, prior: float, method: str, likelihood: str = "gauss",
           sigma_dof: int = 0) -> float:
    return ex.score(n_data, method, likelihood, sigma_dof) - 2.0 * np.log(prior)


def _size_prior(n_pool: int) -> dict:
    """{size: prior of one explanation of that size} of :func:`femcheck.diagnose.evidence.size_prior` for none, the
    ``n_pool`` singles and their pairs."""
    n_sizes = 3 if n_pool >= 2 else 2
    n_pairs = n_pool * (n_pool - 1) // 2
    return {0: 1.0 / n_sizes, 1: 1.0 / (n_sizes * max(n_pool, 1)), 2: 1.0 / (n_sizes * max(n_pairs, 1))}


def _worst_total(ex: evidence.Explanation, n_data: int, prior: dict, sigma_dof: int) -> dict:
    """{likelihood: the largest -2 ln (prior x evidence) of ``ex`` over the evidence approximations}."""
    return {lik: max(_total(ex, n_data, prior[len(ex.ids)], m, lik, sigma_dof) for m in evidence.EVIDENCE_METHODS)
            for lik in evidence.LIKELIHOODS}


def _best_total(explanations, n_data: int, prior: dict, sigma_dof: int = 0) -> dict:
    """{likelihood: an upper bound, under every evidence approximation, of the best -2 ln (prior x evidence) among
    ``explanations``} for each likelihood (Gaussian; Student-t with the readings' ``sigma_dof``)."""
    return {lik: max(min(_total(e, n_data, prior[len(e.ids)], m, lik, sigma_dof) for e in explanations)
                     for m in evidence.EVIDENCE_METHODS) for lik in evidence.LIKELIHOODS}


def _hopeless_pair(best: dict, k: int, prior: dict, n_data: int = 0, sigma_dof: int = 0) -> float:
    """chi^2 above which a pair of ``k`` parameters cannot come within :data:`HOPELESS` of ``best`` (per likelihood,
    :func:`_best_total`) under any evidence approximation and either likelihood.

    A pair's -2 ln (prior x evidence) is at least L(chi^2) - 2 k ln 2 - 2 ln prior_pair, L the likelihood term
    (chi^2 for Gauss, (N + nu) ln(1 + chi^2 / nu) for Student-t; the Occam term is >= -2 k ln 2 under both evidence
    approximations and both likelihoods, the placement penalty >= 0). L is increasing in chi^2, so the bound is the
    inverse image L^-1(best + HOPELESS + 2 k ln 2 + 2 ln prior_pair) (:func:`femcheck.diagnose.evidence.student_chi2`),
    and the stop threshold is the largest over the likelihoods (hopeless under both). Under Student-t the threshold is
    *not* the Gaussian one: the transform compresses large chi^2, so a pair hopeless under Gauss can still matter."""
    if not isinstance(best, dict):
        best = {lik: float(best) for lik in evidence.LIKELIHOODS}
    out = []
    for lik, b in best.items():
        term = b + HOPELESS + 2.0 * k * np.log(2.0) + 2.0 * np.log(prior[2])
        out.append(evidence.student_chi2(term, n_data, sigma_dof) if lik == "student" else term)
    return float(max(out))


def fit_rivals(model, readings, pool, base: FitResult, *, pairs: bool = True, known=None) -> list:
    """Every rival explanation: none, each single effect of ``pool`` and (``pairs``) each pair, as
    :class:`~femcheck.diagnose.evidence.Explanation` with the :class:`FitResult` as payload (and the extended-BIC
    penalty of located effects). Pairs start from the two singles' fitted values (one start, at most 100
    evaluations). ``known``: {frozenset of ids: FitResult} of fits already made with these effects (the greedy
    selection's rounds, several starts), reused instead of refitted.

    A pair fit is stopped after a short probe (``fit_effects(stop_above=...)``) when even a full Gauss-Newton step
    could not bring its chi^2 within :data:`HOPELESS` of the best -2 ln (prior x evidence) found so far, under either
    evidence approximation and either likelihood (the Occam term of a pair is >= -2 k ln 2 under all;
    :func:`_hopeless_pair`): its posterior is then below 2e-9 of the leader's whatever its exact optimum, and its chi^2
    is reported as reached. The floor is a bound only of the linearized problem, so a pair whose better single is
    already within the threshold (``nested_chi2``: the pair nests it, its optimum is at most that chi^2) is never
    stopped: on generated sets those were the pairs the floor wrongly stopped (``python -m femcheck.bench early_stop``,
    docs/diagnose.md "Early stops")."""
    known = known or {}
    n_data = 3 * readings.n_states
    out = [evidence.Explanation((), base.chi2, 0, base)]
    singles = {}
    for eff in pool:
        f = known.get(frozenset([eff.id])) or fit_effects(model, readings, [eff])
        singles[eff.id] = f
        out.append(_explanation(f))
    if pairs:
        prior = _size_prior(len(pool))
        nu = int(getattr(readings, "sigma_dof", 0) or 0)
        best = _best_total(out + [_explanation(f) for ids, f in known.items() if len(ids) == 2], n_data, prior, nu)
        for i, first in enumerate(pool):
            for second in pool[i + 1:]:
                f = known.get(frozenset([first.id, second.id]))
                if f is None:
                    # order the pair by the singles' fit: the better single first
                    a, b = (first, second) if singles[first.id].bic <= singles[second.id].bic else (second, first)
                    start = np.concatenate([singles[a.id].values[0], singles[b.id].values[0]])
                    f = fit_effects(model, readings, [a, b], starts=[start], max_nfev=100,
                                    stop_above=_hopeless_pair(best, len(start), prior, n_data, nu),
                                    nested_chi2=min(singles[a.id].chi2, singles[b.id].chi2))
                ex = _explanation(f)
                out.append(ex)
                worst = _worst_total(ex, n_data, prior, nu)
                best = {lik: min(best[lik], worst[lik]) for lik in best}
    return out


def _key(ex: evidence.Explanation) -> frozenset:
    """The effects of an explanation (a located effect with its legs): two placements of one element type are two
    explanations with the same ids."""
    return frozenset(ex.payload.effects) if ex.payload is not None else frozenset(ex.ids)


#: -2 ln evidence behind the best weighed rival beyond which the unweighed placements of an element type are not
#: evaluated on the chain (:func:`unweighed_explanations`): a weight below e^-50
UNWEIGHED_HOPELESS = 100.0


def _partner_leads(rivals, n_leads: int, bic_margin: float) -> list:
    """The fits of the ``n_leads`` best non-located singles among ``rivals`` that beat none by ``bic_margin``."""
    none = next(ex for ex in rivals if not ex.ids)
    singles = sorted((ex for ex in rivals if len(ex.ids) == 1 and ex.payload is not None
                      and not ex.payload.effects[0].located and ex.payload.bic < none.payload.bic - bic_margin),
                     key=lambda ex: ex.payload.bic)
    return [ex.payload for ex in singles[:n_leads]]


def unweighed_explanations(model, readings, located, rivals, leads) -> list:
    """One explanation per element type (alone, and with each lead of :func:`_partner_leads`) holding the evidence
    of its placements that no fit weighed (:func:`femcheck.diagnose.placement.unweighed_placements`): the posterior of a located cause is then summed over all its placements, the fitted ones exactly and
    the others linearized. These explanations have no fit (``payload`` None, ``fixed_scores`` set): they count in
    the marginal probability of their causes and in ``alternatives``, never as the named explanation."""
    n_data = 3 * readings.n_states
    sd = readings.sigma_dof

    def weighed(others: tuple) -> dict:
        # {element type id: leg sets fitted} among the explanations whose other causes are ``others``
        out = {}
        for ex in rivals:
            effs = getattr(ex.payload, "effects", None)
            if effs is None:
                continue
            loc = [e for e in effs if e.located]
            if len(loc) == 1 and tuple(sorted(e.id for e in effs if not e.located)) == others:
                out.setdefault(loc[0].id, set()).add(loc[0].legs)
        return out

    # an element type whose best placement is this far behind the best weighed rival holds < e^-50 of the mass
    hopeless = min(ex.score(n_data, m, lik, sd) for ex in rivals for m in evidence.EVIDENCE_METHODS
                   for lik in evidence.LIKELIHOODS) + UNWEIGHED_HOPELESS
    out = []
    for lead in [None] + list(leads):
        if lead is None:
            others, background, base = (), None, None
        else:
            ex = _explanation(lead)
            others, background = tuple(sorted(lead.ids)), (list(lead.effects), list(lead.values))
            base = {(m, lik): ex.score(n_data, m, lik, sd) - (evidence.student_term(lead.chi2, n_data, sd)
                                                              if lik == "student" and sd > 0 else lead.chi2)
                    for m in evidence.EVIDENCE_METHODS for lik in evidence.LIKELIHOODS}
        for eff, scores, legs, chi2 in unweighed_placements(model, readings, located, skip=weighed(others),
                                                             background=background, base_scores=base, sigma_dof=sd,
                                                             hopeless_above=hopeless):
            k = len(legs) + (sum(len(v) for v in lead.values) if lead is not None else 0)
            out.append(evidence.Explanation(others + (eff.id,), chi2, k, fixed_scores=scores))
    return out


def located_partners(model, readings, located, screened, rivals, *, n_leads: int = 1,
                     bic_margin: float = 10.0, siblings: bool = False) -> tuple[list, list]:
    """Placements of located causes beyond those in the full pool, and their explanations.

    Two sources, one mechanism:

    * **partners of a pair**: the placement screen (:func:`femcheck.diagnose.placement.screen_placements`) is run again
      on the residual *after* each of the ``n_leads`` best non-located singles of ``rivals`` (the model with that
      effect at its fitted values; only singles that beat none by ``bic_margin``). When another cause dominates the
      residual of the model as given, the screen of the model as given ranks or places the located cause on what that
      cause leaves unexplained, not on the located cause's own signature; re-screened, the located partner is placed
      on the remainder;
    * **placements the data cannot tell apart**: the other refined placements of the first screen (one per element
      type, the ones beyond ``max_located``; e.g. the spherical and the universal joint of the same legs).

    Every new placement (not already among the rivals' effects: only when a screen changes its answer) is fitted
    alone and in a pair with each lead, and joins the rivals, weighed like the others with its extended-BIC
    penalty: the marginal probability of a located cause is then the sum over its weighed placements, and the mass
    is split between element types or leg sets that fit alike. The placements never fitted (the element types not
    refined, leg sets not on the search paths) get their linearized mass from :func:`unweighed_explanations`, alone
    and in a pair with the leads; pairs of a located type with a non-lead cause get none.
    The size prior shares each size's mass over the explanations weighed, so adding placements lowers each single's
    prior slightly. ``siblings`` (opt-in, ``diagnose(located_siblings=True)``): also weigh, for the located placement of
    the pool and the best re-screened one, the same legs with every other element type (a drive, a guideway and the two
    joints of one leg act in series and are often not told apart at a few points). On 120 prior-drawn calibration
    sets it lowered the cause ECE from 0.0168 to 0.0130 (bic; docs/diagnose.md) but cost 20-35 % more time on the
    9-point bench datasets (located case 22.9 s CPU > the 20 s budget), hence off by default. Returns (placements,
    explanations)."""
    n_data = 3 * readings.n_states
    have = {e for ex in rivals for e in ex.payload.effects}
    none = next(ex for ex in rivals if not ex.ids)
    # a lead must beat none by the BIC margin. Not also every located single: a located placement that explains more
    # than any other cause alone can still be the wrong one for the pair (seed-1000 set 1038 of the calibration bench,
    # joint contact compliance + a spherical joint in some legs: with that condition the located cause got 0.005)
    leads = _partner_leads(rivals, n_leads, bic_margin)
    new = []
    for p in screened:   # the refined placements of other element types (the first max_located are in the pool)
        if p.effect not in have and all(p.effect != q.effect for q in new):
            new.append(p)
    rescreened = []
    # the leg scales a screen on a lead's residual found: the start of that pair's fit (the placement's single fit,
    # made without the lead, can be far off where the lead dominates the residual, e.g. friction)
    partner_start = {}
    for li, lead in enumerate(leads):   # the located partner of a pair, placed on what the lead leaves
        for p in screen_placements(model, readings, located, keep=3,
                                   background=(list(lead.effects), list(lead.values))):
            rescreened.append(p)
            if p.values is not None:
                partner_start.setdefault((li, p.effect), np.asarray(p.values, float))
            if p.effect not in have and all(p.effect != q.effect for q in new):
                new.append(p)
    if siblings:
        # the same legs, the other element types: the leg sets a screen keeps are well resolved, the element type in
        # them often is not (a drive, a guideway and the two joints of one leg act in series; at 2-4 points they
        # differ by less than the screen's margin). Weighed, the located mass spreads over the types of those legs
        best_placed = [e for e in have if getattr(e, "located", False)] + [p.effect for p in rescreened[:1]]
        for e in best_placed:
            for other in located:
                sib = other.restricted(e.legs)
                if sib not in have and all(sib != q.effect for q in new):
                    new.append(Placement(sib, None, None, ()))
    out = []
    if not new:
        return [], out
    prior = _size_prior(sum(1 for ex in rivals if len(ex.ids) == 1) + len(new))
    best = _best_total(rivals, n_data, prior, readings.sigma_dof)
    for p in new:
        f = fit_effects(model, readings, [p.effect])
        out.append(_explanation(f))
        for li, lead in enumerate(leads):
            # the lead first, as in the screen's background: a stage-1 lead that sets a whole element column (e.g.
            # actuation_compliance) is applied before the located scales of that column, not over them
            starts = [np.concatenate([lead.values[0], f.values[0]])]
            if (li, p.effect) in partner_start:
                starts.insert(0, np.concatenate([lead.values[0], partner_start[(li, p.effect)]]))
            start = starts[0]
            fp = fit_effects(model, readings, [lead.effects[0], p.effect], starts=starts, max_nfev=100,
                             stop_above=_hopeless_pair(best, len(start), prior, n_data, readings.sigma_dof),
                             nested_chi2=min(lead.chi2, f.chi2))
            out.append(_explanation(fp))
    return new, out


#: the causes for the contact nonlinearity the detailed model has (friction in the joints and guides, Hertz contact
#: laws): a dead band (``clearance``) is named only when it is needed beyond them (:func:`clearance_needed`)
CONTACT_NONLINEARITY = ("friction_hysteresis", "hertz_stiffening")


def clearance_needed(model, readings, chosen, fit: FitResult, folds, threshold: float, bic_margin: float) -> dict:
    """Whether the ``clearance`` of the named explanation ``chosen`` is needed beyond the frictional and Hertz
    nonlinearity.

    A dead band closed by a force adds deflection at small loads and little at large ones; so does a Hertz contact
    law stiffer than modelled, and friction in the joints makes small loads stick. On data whose nonlinearity is the
    contact's own, a ``clearance`` of ~10 um closed at a few N fits it as well as they do, and was named in their
    place. Here the other named causes plus :data:`CONTACT_NONLINEARITY` (those not named, fitted with them) are the
    background; clearance must then still lower the held-out chi^2 by more than the noise ``threshold``
    (2 sqrt(2 N_heldout), as a selection step) *and* the BIC by ``bic_margin``. Returns {"needed": bool, the
    background's ids, the held-out chi^2 and BIC gains}."""
    reg = effect_registry()
    clearance = next(e for e in chosen if e.id == "clearance")
    others = [e for e in chosen if e is not clearance]
    background = others + [reg[i] for i in CONTACT_NONLINEARITY
                           if i in reg and reg[i].applicable(model) and all(e.id != i for e in others)]
    f_bg = fit_effects(model, readings, background)
    i_c = list(fit.effects).index(clearance)
    f_all = fit_effects(model, readings, background + [clearance],
                        starts=[np.concatenate(list(f_bg.values) + [fit.values[i_c]])])
    if f_all.chi2 > fit.chi2 + f_bg.chi2:   # never worse than the background alone
        f_all = fit_effects(model, readings, background + [clearance])
    gain_cv = (cross_validate(model, readings, background, f_bg, folds).chi2
               - cross_validate(model, readings, background + [clearance], f_all, folds).chi2)
    gain_bic = f_bg.bic - f_all.bic
    return {"needed": bool(gain_cv > threshold and gain_bic > bic_margin), "beyond": [e.id for e in background],
            "heldout_chi2_gain": float(gain_cv), "bic_gain": float(gain_bic), "threshold_chi2": float(threshold)}


#: the best pairs holding a located cause whose placements are refitted together (:func:`refit_pair_placements`)
REFIT_PAIRS = 3


def refit_pair_placements(model, readings, located, rivals, *, top: int = REFIT_PAIRS, rounds: int = 2) -> tuple[list, list]:
    """Pairs whose located placement is chosen again with the partner in place: not a greedy first pick.

    A placement is screened on the residual of the model as given (or of one lead), where a second cause's signature
    is still in it: the legs it takes then partly fit that other cause (a guideway placed on five legs with odd factors
    where the guideways of all legs and the cables are softer), and the pair fitted from it stays there. For each of the
    ``top`` best pairs of ``rivals`` (by BIC) that hold a located cause, the placement of each located partner is
    screened again (:func:`femcheck.diagnose.placement.screen_placements`, every element type ranked, the three best
    refined) on the background of the
    other partner at its values *in the pair*, and the pair is refitted jointly from the screened leg scales; with two
    located partners they alternate, ``rounds`` times or until the placements stop changing. Every new pair joins the
    rivals and is weighed like the others (its extended-BIC penalty included). Returns (placements, explanations)."""
    have = {frozenset(ex.payload.effects) for ex in rivals if ex.payload is not None}
    pairs = sorted((ex for ex in rivals if ex.payload is not None and len(ex.payload.effects) == 2
                    and any(e.located for e in ex.payload.effects)), key=lambda ex: ex.payload.bic)[:top]
    placements, out = [], []
    for ex in pairs:
        fit = ex.payload
        for _ in range(rounds):
            changed = False
            # each located partner placed again with the other in place; a non-located partner (a whole-leg factor
            # that took one leg's change of another element) replaced by the placement screened with the located
            # partner in place
            moves = [(i, fit.effects[1 - i]) for i, e in enumerate(fit.effects) if e.located]
            moves += [(1 - i, e) for i, e in enumerate(fit.effects) if e.located and not fit.effects[1 - i].located]
            for i, other in moves:
                eff = fit.effects[i]
                screened = screen_placements(model, readings, located, keep=3,
                                             background=([other], [fit.values[1 - i]]))
                if not screened or screened[0].effect == eff or screened[0].effect.id == other.id:
                    continue
                p = screened[0]
                key = frozenset([other, p.effect])
                if key in have:
                    continue
                start = np.concatenate([fit.values[1 - i], np.asarray(p.values, float)])
                new = fit_effects(model, readings, [other, p.effect], starts=[start], max_nfev=100)
                have.add(key)
                placements.append(p)
                out.append(_explanation(new))
                if new.bic < fit.bic:
                    fit, changed = new, True
                    break
            if not changed:
                break
    log.info("pair placements refitted together: %d new pairs", len(out))
    return placements, out


#: seconds per unit of each phase of :func:`diagnose` (the reference case, 9 points x 6 directions, the whole
#: effect library; measured phase by phase on the shared 2-core machine with the compiled kernels cached, 67 s
#: in all): screening one located effect's placements, one fit of the model as given per fold, one candidate
#: fit of a selection round, one rival pair, weighing one located effect's placements, the baseline per fold.
#: The very first run also compiles the kernels (about 45 s more in the screening): its ETA starts high.
PHASE_S = {"placements": 1.7, "model as given": 0.005, "round": 2.1, "rivals": 0.2, "placements weighed": 0.96,
           "baseline": 0.5}


def diagnosis_phases(n_pool: int, n_located: int, max_effects: int, n_folds: int, max_located: int,
                     pairs: bool, baseline: bool) -> list[tuple[str, float]]:
    """The phases of :func:`diagnose` and their expected costs (s, :data:`PHASE_S` times the phase's count of
    units), for the progress ETA. Phases that do not run weigh (almost) nothing but are still reported."""
    pool = n_pool + min(max_located, n_located)
    located = n_located if max_located > 0 else 0
    n_pairs = max(pool * (pool - 1) / 2, 0) if (pairs and max_effects >= 2) else 0
    eps = 1e-3
    return ([("placements", PHASE_S["placements"] * located + eps), ("model as given", PHASE_S["model as given"] * (1 + n_folds))]
            + [(f"round {k + 1}", PHASE_S["round"] * pool + eps) for k in range(max_effects)]
            + [("rivals", PHASE_S["rivals"] * n_pairs + eps),
               ("placements weighed", PHASE_S["placements weighed"] * located + eps),
               ("baseline", PHASE_S["baseline"] * n_folds if baseline else eps)])


#: |correlation| between a parameter of one named cause and one of another beyond which the data determine only their
#: combination: the two are not both named with confidence (their shared mass is split, :func:`share_collinear`)
COLLINEAR = 0.95


def collinear_causes(fit: FitResult, limit: float = COLLINEAR) -> list[tuple[str, str, float]]:
    """(id_a, id_b, correlation) for each pair of causes of ``fit`` with a parameter pair correlated beyond ``limit``
    (the largest |correlation| of the pair, from the fit's (J^T J)^-1; parameters on a bound do not count)."""
    if fit.correlation is None or len(fit.effects) < 2:
        return []
    edges = np.cumsum([0] + [len(e.params) for e in fit.effects])
    out = []
    for i in range(len(fit.effects)):
        for j in range(i + 1, len(fit.effects)):
            block = fit.correlation[edges[i]:edges[i + 1], edges[j]:edges[j + 1]]
            if np.isfinite(block).any():
                c = block.flat[int(np.nanargmax(np.abs(block)))]
                if abs(c) > limit:
                    out.append((fit.effects[i].id, fit.effects[j].id, float(c)))
    return out


def share_collinear(marginals: dict, weighing: evidence.Weighing, collinear) -> dict:
    """Cause marginals with the mass of the explanations holding *both* causes of a collinear pair split between them.

    With the pair's parameters correlated beyond :data:`COLLINEAR` the data fix one combination: an explanation with
    both says no more than "one of the two, or both", and the two explanations that carry the signal with one cause in
    place of the other fit alike. Their mass is shared: each cause keeps the explanations it is in without the other,
    plus half of those holding both. The two marginals then sum to at most 1, so they cannot both reach 0.9."""
    out = dict(marginals)
    for a, b, _ in collinear:
        both = float(sum(p for ex, p in zip(weighing.explanations, weighing.probability) if a in ex.ids and b in ex.ids))
        out[a] = max(out[a] - 0.5 * both, 0.0)
        out[b] = max(out[b] - 0.5 * both, 0.0)
    return out


#: chi^2 within which a rival that holds another cause in place of a named one fits as well: the part of the named
#: cause's fitted effect that the other cannot reproduce is then below 3 reading sigmas (chi^2 = z^2, z = 3), and
#: these readings cannot separate the two (:func:`alias_swaps`, :func:`alias_groups`)
ALIAS_CHI2 = 9.0


def _swap_candidates(eff, located, reg) -> list:
    """The causes that could stand in place of named cause ``eff`` on the same legs: every other located element type
    at ``eff``'s legs (a uniform placement for a uniform or non-located ``eff``; an element whose uniform change has a
    vocabulary id of its own, e.g. ``actuation_compliance``, by that id)."""
    uniform = not getattr(eff, "located", False) or eff.uniform
    out = []
    for other in located:
        if eff.located and other.element == eff.element:
            continue
        if uniform and other.uniform_cause:
            cand = reg.get(other.uniform_cause)
        else:
            cand = other.uniform_all() if uniform else other.restricted(eff.legs)
        if cand is not None and cand.id != eff.id and cand not in out:
            out.append(cand)
    return out


def alias_swaps(model, readings, located, named: FitResult, rivals) -> list:
    """Rivals that hold, in place of one named cause, another element type on the same legs (:func:`_swap_candidates`),
    the other named causes kept: fitted jointly (the others from their named values) when not already weighed.

    Elements of one leg act in series along it (the proximal tube and the U joint when the joints slip: two springs on
    the link's line), so at the readings' points their changes can look alike. Weighed like every rival, the mass is
    then shared between the placements the data cannot tell apart, and :func:`alias_groups` names them as one group.
    Returns the new explanations."""
    reg = effect_registry()
    have = {_key(ex) for ex in rivals}
    out = []
    for i, eff in enumerate(named.effects):
        others = [e for j, e in enumerate(named.effects) if j != i]
        for cand in _swap_candidates(eff, located, reg):
            effects = others[:i] + [cand] + others[i:]
            if frozenset(effects) in have:
                continue
            values = [v for j, v in enumerate(named.values) if j != i]
            start = np.concatenate(values[:i] + [cand.starts(model)[0]] + values[i:])
            f = fit_effects(model, readings, effects, starts=[start], max_nfev=100)
            have.add(frozenset(effects))
            out.append(_explanation(f))
    log.info("alias swaps of the named causes fitted: %d", len(out))
    return out


def _label(eff) -> str:
    if getattr(eff, "located", False):
        return f"{eff.id}[{'all' if eff.uniform else ','.join(map(str, eff.legs))}]"
    return eff.id


def _same_element(a, b) -> bool:
    """Whether two causes move the same element alone (an element's uniform change that has a vocabulary id of its
    own, e.g. ``actuation_compliance``, is that element's)."""
    return (getattr(a, "uniform_cause", None) == b.id or getattr(b, "uniform_cause", None) == a.id
            or (getattr(a, "located", False) and getattr(b, "located", False) and a.element == b.element))


def _place(eff) -> tuple:
    """The legs a cause moves (a cause of the whole device: all six)."""
    return tuple(getattr(eff, "legs", ())) if getattr(eff, "located", False) else tuple(range(6))


def alias_groups(named: FitResult, weighing: evidence.Weighing, limit: float = ALIAS_CHI2) -> list[dict]:
    """For each named cause, the causes the readings cannot separate from it: those of another id on the same legs
    (:func:`_place`) that take its place in a weighed rival (the other named causes at the same placements) whose
    chi^2 is within ``limit`` of the named explanation's.

    Returns one dict per named cause that has such partners: ``cause`` and ``legs`` of the named one, ``members``
    (the named first; each ``id``, ``legs``, ``delta_chi2`` = rival chi^2 - named chi^2), ``probability`` (the
    posterior mass of the explanations holding one of the members in place of the named cause, the named one
    included) and ``text`` (in words, with the ``femcheck plan`` call that searches for readings to separate them;
    where the two are one column at every reachable reading, e.g. springs in series, none exists)."""
    groups = []
    own = {_key(ex): (ex, p) for ex, p in zip(weighing.explanations, weighing.probability) if ex.payload is not None}
    for i, eff in enumerate(named.effects):
        others = [e for j, e in enumerate(named.effects) if j != i]
        members, mass = [], 0.0
        for key, (ex, p) in own.items():
            extra = key - set(others)
            if len(key) != len(named.effects) or len(extra) != 1:
                continue
            cand = next(iter(extra))
            if cand == eff:
                mass += p
            elif (cand.id != eff.id and not _same_element(cand, eff) and _place(cand) == _place(eff)
                  and abs(ex.chi2 - named.chi2) < limit):
                members.append({"id": cand.id, "legs": list(getattr(cand, "legs", ())), "label": _label(cand),
                                "delta_chi2": float(ex.chi2 - named.chi2)})
                mass += p
        if not members:
            continue
        # one member per cause id: its placement that fits closest to the named one
        members = sorted({m["id"]: m for m in sorted(members, key=lambda m: -abs(m["delta_chi2"]))}.values(),
                         key=lambda m: m["delta_chi2"])
        head = {"id": eff.id, "legs": list(getattr(eff, "legs", ())), "label": _label(eff), "delta_chi2": 0.0}
        ids = ",".join(dict.fromkeys([eff.id] + [m["id"] for m in members]))
        text = (" \u2261 ".join([head["label"]] + [m["label"] for m in members])
                + f": these readings cannot separate them (each fits within chi2 {limit:g} of the other, less than "
                  f"3 reading sigmas of difference); femcheck plan CASE DATA.csv --effects {ids} searches for readings "
                  f"that would")
        groups.append({"cause": eff.id, "legs": head["legs"], "members": [head] + members,
                       "probability": float(min(mass, 1.0)), "text": text})
    return groups


def heldout_losses(model, readings, chosen, fit: FitResult, cv: CrossValidation, cv_base: CrossValidation, folds,
                   known=None) -> dict:
    """{cause id: held-out mean relative deflection error lost (percentage points) when that cause is left out of the
    named explanation ``chosen``}: the others refitted (warm start at their values in ``fit``) and cross-validated on
    the same ``folds``, minus the named explanation's own held-out error ``cv``. The importance of a cause."""
    known = known or {}
    out = {}
    for i, eff in enumerate(chosen):
        others = [e for e in chosen if e is not eff]
        if not others:
            cv_without = cv_base
        else:
            f = known.get(frozenset(e.id for e in others))
            if f is None or list(f.effects) != others:
                start = np.concatenate([v for e, v in zip(chosen, fit.values) if e is not eff])
                f = fit_effects(model, readings, others, starts=[start])
            cv_without = cross_validate(model, readings, others, f, folds)
        out[eff.id] = 100.0 * float(cv_without.error["overall"] - cv.error["overall"])
    return out


def diagnose(model, readings, *, candidates=None, max_effects: int = 2, n_folds: int = 3, shortlist: int = 2,
             bic_margin: float = 10.0, with_baseline: bool = True, rivals_pairs: bool = True,
             max_located: int = 1, evidence_method: str | None = None, likelihood: str | None = None,
             partner_leads: int = 1, located_siblings: bool = False, unweighed_mass: bool = True,
             aliases: bool = True, progress=None) -> Diagnosis:
    """Name the effects that explain ``readings`` beyond ``model`` (see module docstring). Located effects
    (``Effect.located``, the ``<element>_in_legs`` family) are screened for their legs first
    (:func:`femcheck.diagnose.placement.screen_placements`); the ``max_located`` best placements join the
    candidates (alone and in every pair); the other refined placements, and those screened again on the residual
    after the ``partner_leads`` best non-located singles, join as singles and in pairs with those leads
    (:func:`located_partners`). ``evidence_method``: "laplace" | "bic" (default
    :data:`femcheck.diagnose.evidence.EVIDENCE`); ``likelihood``: "gauss" | "student" (default
    :data:`femcheck.diagnose.evidence.LIKELIHOOD`; "student" integrates sigma out when ``readings.sigma_dof`` > 0).
    ``aliases``: weigh, for each named cause, the other element types on its legs in its place (:func:`alias_swaps`)
    and report those the readings cannot separate from it as one group (:func:`alias_groups`).
    ``progress``: an object with ``plan(weights)`` (the expected relative cost of each phase, called once) and
    ``advance(1, description)`` (after each phase), e.g. :class:`femcheck.cli._progress.StageProgress`."""
    if evidence_method is not None and evidence_method not in evidence.EVIDENCE_METHODS:
        raise ValueError(f"evidence_method: {evidence_method!r}; expected one of {', '.join(evidence.EVIDENCE_METHODS)}")
    if likelihood is not None and likelihood not in evidence.LIKELIHOODS:
        raise ValueError(f"likelihood: {likelihood!r}; expected one of {', '.join(evidence.LIKELIHOODS)}")
    if readings.n_cases == 0 or len(set(readings.case_point)) < 2:
        from femcheck.errors import MeasuredDataError
        raise MeasuredDataError(readings.source, None, "point", "a diagnosis needs preload and total readings at two or "
                                "more points (leave-points-out cross-validation)")
    reg = effect_registry()
    chosen_ids = [c for c in (candidates or sorted(reg)) if c != "none" and reg[c].applicable(model)]
    pool = [reg[c] for c in chosen_ids if not reg[c].located]
    located = [reg[c] for c in chosen_ids if reg[c].located]
    phases = diagnosis_phases(len(pool), len(located), max_effects, n_folds, max_located, rivals_pairs, with_baseline)
    if progress is not None:
        progress.plan([w for _name, w in phases])
    step = (lambda desc: progress.advance(1, desc)) if progress is not None else (lambda desc: None)
    # the nonlinear leg choice refines the three linearly best element types (at least max_located): the linear
    # ranking at scale 1 can put the wrong type first when a leg is far from 1 (e.g. a near-rigid guideway); the
    # max_located best *refined* placements join the candidates
    folds = point_folds(readings, n_folds)
    # one reading per state: sigma from the richest rival, once, before the search (every fit below uses it)
    readings, rival_note = sigma_from_richest_rival(model, readings, pool, folds)
    screened = (screen_placements(model, readings, located, keep=max(3, max_located))
                if located and max_located > 0 else [])
    placements = screened[:max_located]
    pool += [p.effect for p in placements]
    step("placements screened")
    base = fit_effects(model, readings, [])
    cv_base = cross_validate(model, readings, [], base, folds)
    step("model as given fitted")
    n_total = 3 * readings.n_states
    threshold = 2.0 * np.sqrt(2.0 * n_total)
    chosen, cur_fit, cur_cv = [], base, cv_base
    steps = []
    known = {}
    for rnd in range(max_effects):
        fits = []
        for eff in pool:
            if eff in chosen:
                continue
            starts, stop = None, None
            if chosen:
                prev = np.concatenate(cur_fit.values)
                starts = [np.concatenate([prev, s]) for s in eff.starts(model)]
                if len(chosen) == 1 and rivals_pairs:
                    # a pair that can neither pass the BIC margin nor matter as a rival is not fitted to the end
                    k = len(starts[0])
                    pen = sum(getattr(e, "penalty", 0.0) for e in chosen + [eff])
                    accept = cur_fit.bic - bic_margin - k * np.log(n_total) - pen
                    prior = _size_prior(len(pool))
                    rivals_best = _best_total([evidence.Explanation((), base.chi2, 0, base)]
                                              + [_explanation(f) for ids, f in known.items() if len(ids) == 1],
                                              n_total, prior, readings.sigma_dof)
                    stop = max(accept, _hopeless_pair(rivals_best, k, prior, n_total, readings.sigma_dof))
            nested = min([cur_fit.chi2] + [f.chi2 for ids, f in known.items() if ids == frozenset([eff.id])]) \
                if chosen else None
            fits.append(fit_effects(model, readings, chosen + [eff], starts=starts, stop_above=stop, nested_chi2=nested))
            known[frozenset(fits[-1].ids)] = fits[-1]
        fits.sort(key=lambda f: f.bic)
        rows = [{"round": rnd + 1, "effects": list(f.ids), "chi2": f.chi2, "bic": f.bic, "delta_bic": cur_fit.bic - f.bic}
                for f in fits]
        short = [f for f in fits[:shortlist] if cur_fit.bic - f.bic > bic_margin]
        best, best_cv = None, None
        for f in short:
            cv = cross_validate(model, readings, list(f.effects), f, folds)
            row = next(r for r in rows if r["effects"] == list(f.ids))
            row.update(heldout_chi2=cv.chi2, heldout_error=cv.error["overall"])
            if best_cv is None or cv.chi2 < best_cv.chi2:
                best, best_cv = f, cv
        accepted = best is not None and cur_cv.chi2 - best_cv.chi2 > threshold
        for r in rows:
            r["accepted"] = bool(accepted and r["effects"] == list(best.ids))
        steps.extend(rows)
        log.info("round %d: best %s (dBIC %.1f), held-out chi2 %.1f -> %s, accepted %s", rnd + 1,
                 fits[0].ids if fits else "-", cur_fit.bic - fits[0].bic if fits else 0.0, cur_cv.chi2,
                 f"{best_cv.chi2:.1f}" if best_cv else "-", accepted)
        step(f"selection round {rnd + 1}")
        if not accepted:
            break
        chosen, cur_fit, cur_cv = list(best.effects), best, best_cv
    if chosen and not cur_cv.error["overall"] < cv_base.error["overall"]:
        log.info("selected %s lowers the held-out chi^2 but not the held-out relative error: answer none",
                 "+".join(e.id for e in chosen))
        chosen, cur_fit, cur_cv = [], base, cv_base
    # weigh every rival (none, singles, pairs up to max_effects) by BIC evidence; the leader is the answer
    for rnd_left in range(rnd + 1, max_effects):
        step(f"selection round {rnd_left + 1} (not needed)")
    rivals = fit_rivals(model, readings, pool, base, pairs=max_effects >= 2 and rivals_pairs, known=known)
    step("rival explanations fitted")
    partners = []
    if located and max_located > 0 and partner_leads >= 0:
        partners, extra = located_partners(model, readings, located, screened[max_located:], rivals,
                                           n_leads=partner_leads if max_effects >= 2 and rivals_pairs else 0,
                                           bic_margin=bic_margin, siblings=located_siblings)
        rivals += extra
        if max_effects >= 2 and rivals_pairs:
            refit, extra = refit_pair_placements(model, readings, located, rivals)
            partners += refit
            rivals += extra
    if located and max_located > 0 and unweighed_mass:
        leads = _partner_leads(rivals, partner_leads, bic_margin) if max_effects >= 2 and rivals_pairs else []
        rivals += unweighed_explanations(model, readings, located, rivals, leads)
    if located and max_located > 0 and chosen and aliases:
        rivals += alias_swaps(model, readings, located, cur_fit, rivals)
    step("placements weighed")
    greedy_ids = tuple(e.id for e in chosen)
    greedy_key = frozenset(chosen)
    for ex in rivals:   # the greedy fit (joint, several starts) is at least as good as the warm-started rival
        if _key(ex) == greedy_key and ex.chi2 > cur_fit.chi2:
            rivals[rivals.index(ex)] = _explanation(cur_fit)
    if not any(_key(ex) == greedy_key for ex in rivals):   # e.g. three effects named
        rivals.append(_explanation(cur_fit))
    named = next(ex for ex in rivals if _key(ex) == greedy_key)
    # the named causes are the cross-validated greedy choice; the verdict is the goodness of fit of that choice
    w = evidence.weigh(rivals, 3 * readings.n_states, chosen=named, sigma_dof=readings.sigma_dof,
                       method=evidence_method, likelihood=likelihood)
    if greedy_ids and w.probability[0] < 0.01:
        # the evidence over all rivals contradicts the greedy path (e.g. a misfit it had to patch): name the leader
        lead = max(((p, ex) for p, ex in zip(w.probability, w.explanations) if ex.payload is not None),
                   key=lambda t: t[0])[1]
        log.info("greedy %s has posterior %.3g; naming the evidence leader %s", "+".join(greedy_ids), w.probability[0],
                 lead.name)
        chosen, cur_fit = list(lead.payload.effects), lead.payload
        cur_cv = cross_validate(model, readings, chosen, cur_fit, folds) if chosen else cv_base
        greedy_ids = tuple(e.id for e in chosen)
        w = evidence.weigh(rivals, 3 * readings.n_states, chosen=lead, sigma_dof=readings.sigma_dof,
                           method=evidence_method, likelihood=likelihood)
    clearance_check = None
    if any(e.id == "clearance" for e in chosen):
        clearance_check = clearance_needed(model, readings, chosen, cur_fit, folds, threshold, bic_margin)
        if not clearance_check["needed"]:
            # the dead band stands in for contact nonlinearity: name the evidence leader among the explanations
            # without a clearance
            lead = max(((p, ex) for p, ex in zip(w.probability, w.explanations)
                        if ex.payload is not None and "clearance" not in ex.ids), key=lambda t: t[0])[1]
            log.info("clearance not needed beyond %s: naming %s", "+".join(clearance_check["beyond"]), lead.name)
            chosen, cur_fit = list(lead.payload.effects), lead.payload
            cur_cv = cross_validate(model, readings, chosen, cur_fit, folds) if chosen else cv_base
            w = evidence.weigh(rivals, 3 * readings.n_states, chosen=lead, sigma_dof=readings.sigma_dof,
                               method=evidence_method, likelihood=likelihood)
            c = clearance_check
            p_cl = float(sum(p for ex, p in zip(w.explanations, w.probability) if "clearance" in ex.ids))
            w = dataclasses.replace(w, ambiguous=True, ambiguity=(w.ambiguity + "; " if w.ambiguity else "") + (
                f"clearance (probability {p_cl:.2f} among the explanations weighed) is not needed beyond "
                f"{' + '.join(c['beyond'])}: with them it lowers the held-out chi2 by {c['heldout_chi2_gain']:.1f} "
                f"(noise threshold {c['threshold_chi2']:.1f}) and the BIC by {c['bic_gain']:.1f}; its dead band "
                f"stands in for contact nonlinearity, and is not named"))
    # structured lack of fit (femcheck.diagnose.lack_of_fit): a compliance-shaped residual that the overall chi^2
    # spreads over all readings. The verdict turns unexplained only when the named explanation *and* the best
    # explanation of the vocabulary (the evidence leader) both leave one: an effect below the held-out selection's
    # detection limit that a vocabulary cause would fit is not "unexplained"
    lof = _lack_of_fit(readings, cur_fit)
    if lof.p_value < evidence.ALPHA and w.verdict != "unexplained":
        lead = max(((p, ex) for p, ex in zip(w.probability, w.explanations) if ex.payload is not None),
                   key=lambda t: t[0])[1].payload
        lof_lead = lof if lead is cur_fit else _lack_of_fit(readings, lead)
        if lof_lead.p_value < evidence.ALPHA:
            excess_none = _lack_of_fit(readings, base)
            frac = (lof.chi2 - lof.dof * lof.pure_error_ratio) / max(excess_none.chi2 - excess_none.dof
                                                                       * excess_none.pure_error_ratio, 1e-12)
            w = dataclasses.replace(w, verdict="unexplained",
                                    unexplained_fraction=max(w.unexplained_fraction, float(np.clip(frac, 0.0, 1.0))))
    if w.verdict == "explained" and cur_fit.on_bound:
        # a cause that needs a parameter on its bound stands in for something the vocabulary cannot express
        w = dataclasses.replace(w, verdict="unexplained")
    drift_z = readings.trial_drift_m / readings.trial_drift_sigma_m if readings.trial_drift_sigma_m > 0 else 0.0
    if abs(drift_z) > DRIFT_Z:
        # no effect of the vocabulary depends on trial order: a significant drift is unexplained by construction
        w = dataclasses.replace(w, verdict="unexplained")
    p_lead = w.probability[0]   # the named explanation goes first
    # marginal probability of each named cause: the sum over all explanations that contain it (for a located cause,
    # over all its weighed placements)
    marg = {e.id: min(1.0, float(sum(p for ex, p in zip(w.explanations, w.probability) if e.id in ex.ids)))
            for e in chosen}
    collinear = collinear_causes(cur_fit)
    if collinear:
        marg = share_collinear(marg, w, collinear)
        pairs = "; ".join(f"{a} and {b} (parameter correlation {c:+.3f})" for a, b, c in collinear)
        ids = ",".join(dict.fromkeys(x for a, b, _ in collinear for x in (a, b)))
        w = dataclasses.replace(w, ambiguous=True, ambiguity=(
            (w.ambiguity + "; " if w.ambiguity else "") + f"{pairs}: the data fix a combination, not each; their "
            f"probability is shared. Measurements that separate them: femcheck plan CASE DATA.csv --effects {ids}"))
    groups = alias_groups(cur_fit, w) if aliases else []
    if groups:
        w = dataclasses.replace(w, ambiguous=True, ambiguity=(w.ambiguity + "; " if w.ambiguity else "")
                                + "; ".join(g["text"] for g in groups))
    loss = heldout_losses(model, readings, chosen, cur_fit, cur_cv, cv_base, folds, known)
    causes = tuple(Cause(id=e.id, location=e.location(cur_fit.values[i], cur_fit.ci_low[i], cur_fit.ci_high[i]),
                         params=cur_fit.params(i), params_ci=cur_fit.params_ci(i), probability=marg[e.id],
                         on_bound=tuple(n for n in cur_fit.on_bound if n.startswith(e.id + ".")),
                         element=getattr(e, "element", "") if e.located else "", legs=tuple(getattr(e, "legs", ())),
                         heldout_loss_pct=loss[e.id])
                   for i, e in enumerate(chosen))
    # importance order: the cause whose absence costs the most held-out error first
    causes = tuple(sorted(causes, key=lambda c: -c.heldout_loss_pct))
    if not causes:
        causes = (Cause(id="none", location="", params={}, params_ci={}, probability=float(p_lead)),)
    base_err = None
    if with_baseline:
        from femcheck.diagnose.baseline import baseline
        try:
            b = baseline(model, readings, folds)
            base_err = residuals.mean_by_axis(readings, residuals.case_errors(readings, b.heldout_delta)["vector"])
        except Exception as exc:  # the baseline is informative only; never fail a diagnosis on it
            log.warning("seed 001 baseline failed: %s", exc)
    step("baseline fitted")
    return Diagnosis(model_name=model.name, causes=causes, significant=bool(chosen), base=base, fit=cur_fit,
                     cv_before=cv_base, cv_after=cur_cv, steps=tuple(steps), folds=folds,
                     warnings=tuple(cur_fit.warnings), noise_threshold=float(threshold), baseline_error=base_err,
                     readings=readings, weighing=w, placements=tuple(placements), lack_of_fit=lof,
                     partner_placements=tuple(partners), collinear=tuple(collinear), sigma_note=rival_note,
                     clearance_check=clearance_check, alias_groups=tuple(groups))
