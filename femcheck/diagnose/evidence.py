"""Goodness of fit, evidence weights and the verdict of a diagnosis.

Generic: it knows nothing of the device. It takes, per rival explanation, the chi^2 of its weighted
residual vector r = (model - measured) / sigma (N data), and its number of fitted parameters k, and
returns

* the goodness of fit of each: chi^2 / dof with dof = N - k and the upper-tail p-value
  P(chi^2_dof >= chi^2) for a stated sigma (Gaussian noise; Press et al., Numerical Recipes §15.1), or the
  lack-of-fit F test P(F(dof, nu) >= chi^2 / dof) when sigma was estimated from replicates with nu dof;
* posterior probabilities over the explanations, ``P(M_i | D) = pi_i Z_i / sum_j pi_j Z_j`` with a prior that gives
  every explanation size (none, singles, pairs) equal mass, shared equally within the size (Scott & Berger 2010),
  and one of two approximations of the evidence Z = p(D | M) (``method``):

  - ``"laplace"`` (:func:`laplace_score`): the Laplace approximation with the stated parameter prior of
    :mod:`femcheck.diagnose.prior` (MacKay, Information Theory, Inference and Learning Algorithms, 2003, ch. 27-28;
    Kass & Raftery, JASA 90 (1995) 773, §4.1.1),
    ``ln Z = ln L(x*) + ln p(x*) + (k/2) ln 2 pi - 1/2 ln det H``, H the Hessian of the negative log posterior
    (Gauss-Newton: J^T J + W^-2 in the weighted residuals' Jacobian J, W the prior standard deviations);
  - ``"bic"``: the Schwarz criterion ``-2 ln Z ~ chi^2_min + k ln N`` (Schwarz 1978; Kass & Raftery §4.1.3),
    the Laplace evidence's large-N limit with a unit-information prior;

  an Explanation without the Laplace ingredients (``occam`` None) is weighed by BIC. The default (:data:`EVIDENCE`)
  is ``"bic"``: on the calibration bench (``femcheck.bench.calibration``, 120 sets drawn from the Laplace prior) its
  cause marginals were the better calibrated (ECE 0.033 against 0.038; docs/diagnose.md);

  and one of two likelihoods (``likelihood``, :data:`LIKELIHOOD`): ``"gauss"``, -2 ln L = chi^2 with sigma known,
  or ``"student"`` (:func:`student_term`), which integrates sigma^2 out when it was estimated from the trial scatter
  with nu = ``sigma_dof`` > 0 degrees of freedom (s^2 ~ sigma^2 chi^2_nu / nu; the scaled-inverse-chi^2 posterior
  of sigma^2 given the scatter, Gelman et al., Bayesian Data Analysis 3rd ed. §3.2, §14; Box & Tiao 1973 §2.4). The
  N weighted residuals are then multivariate Student-t with nu dof:
  ``-2 ln L = (N + nu) ln(1 + chi^2 / nu) + const``, -> chi^2 + const as nu -> infinity, and the Gaussian limit is
  used when ``sigma_dof`` = 0 (sigma from the dial quantum or stated). Differences between rivals with chi^2 ~ N
  are almost unchanged; for misfits (chi^2 >> N) they are compressed. In the Laplace evidence the Hessian of the
  negative log likelihood (N + nu)/2 ln(1 + chi^2(x)/nu) at its optimum (grad chi^2 = 0, Gauss-Newton
  grad grad chi^2 = 2 J^T J) is c J^T J with ``c = (N + nu) / (nu + chi^2_min)`` (:func:`student_curvature`),
  so A = J^T J becomes c A in :func:`laplace_score` (``FitResult.occam_student``); BIC keeps k ln N. The default
  likelihood is ``"gauss"``: on 80 calibration sets (sigma_dof > 0 on all) the Student-t one changed the BIC cause ECE
  by -0.0009 (0.0252 -> 0.0243), within the sampling noise (docs/diagnose.md, "sigma's own uncertainty");
* the ambiguity between the named explanation and its strongest rival that is neither a sub- nor a
  superset of it: they are called *not separable* when their posterior ratio is below ``ambiguity_ratio`` (default 3, |Delta BIC| < 2.2: "not worth more than a
  bare mention" on Kass & Raftery's scale);
* the verdict, exactly one of ``none`` | ``explained`` | ``unexplained``:
  ``none`` when the no-effect explanation leads and fits within noise (p >= ``alpha``), ``explained``
  when another explanation leads and fits within noise, ``unexplained`` when the leading explanation
  still leaves a significant residual (p < ``alpha``);
* ``unexplained_fraction``: the share of the excess chi^2 over noise of the no-effect model that the
  leading explanation leaves, ``max(chi2_best - dof_best, 0) / max(chi2_none - dof_none, eps)`` in [0, 1],
  and 0 when the named explanation fits within noise.

A future serial-robot diagnosis uses it with its own residual model: only chi^2, N and k enter.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from scipy import stats

#: verdict significance level: a residual whose p-value is below it is not noise. Not 0.01: the true model on
#: simulated 10 um-quantized readings with 3 um noise gives chi^2/dof 1.1-1.2 (measured, 3 seeds; the mean of
#: quantized readings is not Gaussian), p ~ 0.01; out-of-vocabulary effects give chi^2/dof >= 4
ALPHA = 1e-3
#: posterior ratio of leader to runner-up below which the two are reported as not separable
AMBIGUITY_RATIO = 3.0

VERDICTS = ("none", "explained", "unexplained")
EVIDENCE_METHODS = ("laplace", "bic")
#: the default evidence approximation (the better calibrated on the calibration bench, docs/diagnose.md)
EVIDENCE = "bic"
LIKELIHOODS = ("gauss", "student")
#: the default likelihood: Gaussian with sigma known. The Student-t one did not change the calibration beyond sampling
#: noise with BIC on 80 bench sets (cause ECE 0.0252 -> 0.0243; docs/diagnose.md, "sigma's own uncertainty")
LIKELIHOOD = "gauss"


def _check_likelihood(likelihood: str | None) -> str:
    likelihood = likelihood or LIKELIHOOD
    if likelihood not in LIKELIHOODS:
        raise ValueError(f"likelihood {likelihood!r}; expected one of {', '.join(LIKELIHOODS)}")
    return likelihood


def student_term(chi2, n_data: int, sigma_dof: int):
    """-2 ln L of N = ``n_data`` weighted residuals with sum of squares ``chi2`` when sigma^2 is integrated out
    (module docstring): ``(N + nu) ln(1 + chi2 / nu)`` for nu = ``sigma_dof`` > 0, up to the constant
    -2 ln Gamma((nu + N)/2) + 2 ln Gamma(nu/2) + N ln(nu pi s^2) shared by all rivals of the same data (the
    multivariate Student-t density with nu dof and scale s^2 I, BDA3 §3.2 / A.1); ``chi2`` itself (the Gaussian
    limit nu -> infinity) when ``sigma_dof`` = 0. Monotone in chi2; array ``chi2`` allowed."""
    nu = int(sigma_dof)
    if nu <= 0:
        return chi2
    out = (n_data + nu) * np.log1p(np.asarray(chi2, float) / nu)
    return float(out) if np.ndim(out) == 0 else out


def student_chi2(term: float, n_data: int, sigma_dof: int) -> float:
    """Inverse of :func:`student_term` in chi2: the chi^2 whose Student-t -2 ln L is ``term``."""
    nu = int(sigma_dof)
    if nu <= 0:
        return float(term)
    return float(nu * np.expm1(min(term / (n_data + nu), 700.0)))


def student_curvature(chi2: float, n_data: int, sigma_dof: int) -> float:
    """c = (N + nu) / (nu + chi2): the Student-t negative log likelihood's Hessian at its optimum is c J^T J where the
    Gaussian one is J^T J (module docstring); 1 for ``sigma_dof`` = 0."""
    nu = int(sigma_dof)
    return 1.0 if nu <= 0 else float((n_data + nu) / (nu + chi2))


@dataclasses.dataclass(frozen=True)
class Explanation:
    """A rival explanation: ``ids`` the causes (empty = none), ``chi2`` of its fitted weighted residuals,
    ``n_params`` its fitted parameter count, ``payload`` anything the caller wants back (e.g. a fit)."""

    ids: tuple[str, ...]
    chi2: float
    n_params: int
    payload: object = dataclasses.field(default=None, compare=False, repr=False)
    #: extra -2 ln prior of a model chosen by a search over candidates, e.g. the extended BIC's 2 ln C(p, k)
    #: for k places picked among p (Chen & Chen, Biometrika 95 (2008) 759); 0 for a fixed model
    penalty: float = 0.0
    #: Laplace Occam term -2 ln Z - chi^2 (:func:`laplace_score`); None: weigh this explanation by BIC
    occam: float | None = None
    #: Laplace Occam term of the Student-t likelihood, -2 ln Z - :func:`student_term` (:func:`laplace_score` with
    #: ``curvature`` = :func:`student_curvature` for the readings' sigma_dof); None: use ``occam``
    occam_student: float | None = None
    #: -2 ln Z already summed over a family of models, by ("bic" | "laplace", "gauss" | "student"); ``score``
    #: returns it as is (e.g. the linearized sum over the leg sets of a located cause that no fit weighed,
    #: :func:`femcheck.diagnose.placement.unweighed_placements`); None for a fitted explanation
    fixed_scores: dict | None = dataclasses.field(default=None, compare=False, repr=False)

    def score(self, n_data: int, method: str | None = None, likelihood: str | None = None,
              sigma_dof: int = 0) -> float:
        """-2 ln (evidence) up to a constant shared by all explanations, plus the placement ``penalty``.
        ``likelihood`` "gauss" | "student" (default :data:`LIKELIHOOD`); "student" with ``sigma_dof`` > 0 uses
        :func:`student_term` in place of chi^2 (and ``occam_student`` for Laplace), the Gaussian limit otherwise."""
        method = method or EVIDENCE
        if method not in EVIDENCE_METHODS:
            raise ValueError(f"evidence method {method!r}; expected one of {', '.join(EVIDENCE_METHODS)}")
        student = _check_likelihood(likelihood) == "student" and int(sigma_dof) > 0
        if self.fixed_scores is not None:
            return float(self.fixed_scores[(method, "student" if student else "gauss")])
        lik = student_term(self.chi2, n_data, sigma_dof) if student else float(self.chi2)
        if method == "laplace" and (self.occam is not None or self.n_params == 0):
            occam = self.occam_student if student and self.occam_student is not None else self.occam
            return float(lik + (occam or 0.0) + self.penalty)
        return bic(lik, self.n_params, n_data) + self.penalty

    @property
    def name(self) -> str:
        return "+".join(self.ids) if self.ids else "none"


def goodness(chi2: float, dof: int, sigma_dof: int = 0) -> tuple[float, float]:
    """(chi^2 / dof, p-value); dof is clipped to >= 1.

    Known sigma (``sigma_dof`` = 0): P(X >= chi^2), X ~ chi^2_dof. Sigma estimated from replicate scatter with
    ``sigma_dof`` degrees of freedom: the lack-of-fit F test, P(F >= chi^2 / dof), F ~ F(dof, sigma_dof)
    (e.g. Draper & Smith, Applied Regression Analysis §2.1), which allows for the error of the sigma estimate.
    """
    dof = max(int(dof), 1)
    if sigma_dof > 0:
        return float(chi2 / dof), float(stats.f.sf(chi2 / dof, dof, int(sigma_dof)))
    return float(chi2 / dof), float(stats.chi2.sf(chi2, dof))


def bic(chi2: float, n_params: int, n_data: int) -> float:
    """Schwarz criterion chi^2 + k ln N (-2 ln evidence up to a model-independent constant)."""
    return float(chi2 + n_params * np.log(max(n_data, 1)))


def size_prior(explanations) -> np.ndarray:
    """(n,) prior over the rivals: every explanation size (none, singles, pairs, ...) gets the same mass, shared
    equally within the size (the multiplicity correction of Scott & Berger, Ann. Stat. 38 (2010) 2587). With
    equal priors per explanation, ten causes would give the 45 pairs 80 % of the prior mass before any data."""
    sizes = np.array([len(e.ids) for e in explanations])
    uniq, count = np.unique(sizes, return_counts=True)
    per = {int(k): 1.0 / (len(uniq) * c) for k, c in zip(uniq, count)}
    return np.array([per[int(k)] for k in sizes])


def laplace_score(chi2: float, jacobian: np.ndarray, x: np.ndarray, mu: np.ndarray, sd: np.ndarray,
                  mass: np.ndarray | None = None, on_bound: np.ndarray | None = None, curvature: float = 1.0) -> float:
    """-2 ln Z of the Laplace approximation, up to the model-independent likelihood constant N ln 2 pi + 2 sum ln sigma.

    ``chi2``: chi^2 at the maximum-likelihood point ``x`` (k,) (scaled coordinates); ``jacobian`` (N, k) of the
    weighted residuals there; prior x ~ N(``mu``, diag ``sd``^2), truncated so that ``mass`` (k,) of it lies inside the
    bounds (density 1 / mass inside). With A = J^T J, P = diag(sd^-2), d = x - mu and W = diag(sd):

        -2 ln Z = chi2 + d^T (P - P (A + P)^-1 P) d + ln det(I + W A W) + 2 sum ln mass + 2 ln 2 * n_on_bound,

    the second term the chi^2 + prior penalty at the maximum a posteriori point (one Gauss-Newton step from x), the
    third the posterior volume over the prior volume (the Occam factor; -> k ln N + O(1) for N data, i.e. BIC). Exact
    for a linear model with an untruncated prior. A parameter on its bound at the optimum (``on_bound``) keeps about
    half of the Gaussian posterior mass: ln 2 each (the half-Gaussian Laplace approximation).

    ``curvature`` c scales A to c A (the likelihood's Hessian); the Student-t likelihood passes
    c = :func:`student_curvature` and its -2 ln L (:func:`student_term`) as ``chi2``."""
    J = np.asarray(jacobian, float)
    k = J.shape[1]
    if k == 0:
        return float(chi2)
    A = float(curvature) * (J.T @ J)
    P = np.diag(1.0 / np.asarray(sd, float) ** 2)
    d = np.asarray(x, float) - np.asarray(mu, float)
    quad = float(d @ (P - P @ np.linalg.solve(A + P, P)) @ d)
    W = np.diag(np.asarray(sd, float))
    sign, logdet = np.linalg.slogdet(np.eye(k) + W @ A @ W)
    out = float(chi2) + max(quad, 0.0) + float(logdet)
    if mass is not None:
        out += 2.0 * float(np.sum(np.log(np.clip(mass, 1e-300, 1.0))))
    if on_bound is not None:
        out += 2.0 * np.log(2.0) * int(np.sum(on_bound))
    return out


def posterior(explanations, n_data: int, method: str | None = None, likelihood: str | None = None,
              sigma_dof: int = 0) -> np.ndarray:
    """(n,) posterior probabilities (``method`` "laplace" | "bic", default :data:`EVIDENCE`; ``likelihood`` "gauss" |
    "student", default :data:`LIKELIHOOD`, with the readings' ``sigma_dof``) with the size prior of
    :func:`size_prior` (sum 1)."""
    b = np.array([e.score(n_data, method, likelihood, sigma_dof) for e in explanations], float)
    w = np.exp(-0.5 * (b - b.min())) * size_prior(explanations)
    return w / w.sum()


@dataclasses.dataclass(frozen=True)
class Weighing:
    """Result of :func:`weigh`: explanations sorted by decreasing ``probability``; ``verdict``; goodness of the
    leader (``chi2_per_dof``, ``p_value``) and of none (``chi2_per_dof_none``, ``p_value_none``);
    ``ambiguous`` and its sentence ``ambiguity``; ``unexplained_fraction``."""

    explanations: tuple[Explanation, ...]
    probability: tuple[float, ...]
    n_data: int
    verdict: str
    chi2_per_dof: float
    p_value: float
    chi2_per_dof_none: float
    p_value_none: float
    unexplained_fraction: float
    ambiguous: bool
    ambiguity: str
    method: str = "bic"
    likelihood: str = "gauss"
    sigma_dof: int = 0

    @property
    def best(self) -> Explanation:
        return self.explanations[0]

    def alternatives(self, top: int = 10) -> list[dict]:
        out = []
        for e, p in zip(self.explanations[1:top + 1], self.probability[1:top + 1]):
            row = {"ids": list(e.ids) or ["none"], "probability": p, "chi2": e.chi2, "n_params": e.n_params,
                   "bic": bic(e.chi2, e.n_params, self.n_data) + e.penalty,
                   "minus2_log_evidence": e.score(self.n_data, self.method, self.likelihood, self.sigma_dof)}
            # causes with a place (e.g. two placements of one located cause share their ids): their legs
            legs = {c.id: list(c.legs) for c in getattr(e.payload, "effects", ()) if getattr(c, "located", False)}
            if legs:
                row["legs"] = legs
            if e.fixed_scores is not None:   # no fit: a summed family of placements
                row["bic"] = float(e.fixed_scores[("bic", "gauss")])
                row["placements"] = "the leg sets no fit weighed (linearized sum)"
            out.append(row)
        return out


def weigh(explanations, n_data: int, *, chosen=None, sigma_dof: int = 0, alpha: float = ALPHA,
          ambiguity_ratio: float = AMBIGUITY_RATIO, method: str | None = None,
          likelihood: str | None = None) -> Weighing:
    """Weigh rival ``explanations`` (must include the no-effect one, ``ids == ()``) of ``n_data`` residuals.

    ``chosen``: the explanation the caller names (e.g. after a held-out check), as its ids or as one of
    ``explanations`` itself (needed when two rivals share their ids, e.g. two placements of one located cause);
    default the posterior leader. The verdict is the goodness of fit of the named explanation. ``likelihood``: "gauss" |
    "student" (default :data:`LIKELIHOOD`; "student" integrates sigma out when ``sigma_dof`` > 0)."""
    ex = list(explanations)
    nones = [e for e in ex if not e.ids]
    if not nones:
        raise ValueError("weigh needs the no-effect explanation (ids == ()) among the rivals")
    method = method or EVIDENCE
    likelihood = _check_likelihood(likelihood)
    p = posterior(ex, n_data, method, likelihood, sigma_dof)
    order = np.argsort(-p, kind="stable")
    ex, p = [ex[i] for i in order], p[order]
    none = nones[0]
    if chosen is None:
        best = ex[0]
    elif isinstance(chosen, Explanation):
        best = next((e for e in ex if e is chosen), None)
    else:
        best = next((e for e in ex if set(e.ids) == set(chosen)), None)
    if best is None:
        name = chosen.name if isinstance(chosen, Explanation) else "+".join(chosen) or "none"
        raise ValueError(f"the chosen explanation {name} is not among the rivals")
    if best is not ex[0]:   # the named explanation goes first, the others keep their posterior order
        j = ex.index(best)
        ex = [best] + ex[:j] + ex[j + 1:]
        p = np.concatenate([[p[j]], p[:j], p[j + 1:]])
    dof_b, dof_n = n_data - best.n_params, n_data - none.n_params
    c_b, p_b = goodness(best.chi2, dof_b, sigma_dof)
    c_n, p_n = goodness(none.chi2, dof_n, sigma_dof)
    if p_b < alpha:
        verdict = "unexplained"
    elif not best.ids:
        verdict = "none"
    else:
        verdict = "explained"
    excess_none = max(none.chi2 - dof_n, 1e-12)
    # a residual within noise leaves nothing unexplained (the none model's excess is then noise itself)
    frac = 0.0 if p_b >= alpha else float(np.clip(max(best.chi2 - max(dof_b, 1), 0.0) / excess_none, 0.0, 1.0))
    # ambiguity: the named explanation against its strongest *different* rival (neither contains the other:
    # a nested rival only adds or drops a cause and shows up in that cause's marginal probability instead)
    named = set(best.ids)
    rival = next((j for j in range(1, len(ex)) if not (set(ex[j].ids) <= named or named <= set(ex[j].ids))), None)
    ambiguous = rival is not None and p[rival] > 0 and p[0] / p[rival] < ambiguity_ratio
    text = (f"{ex[0].name} {p[0]:.2f} vs {ex[rival].name} {p[rival]:.2f}: not separable with these measurements"
            if ambiguous else "")
    return Weighing(tuple(ex), tuple(map(float, p)), int(n_data), verdict, c_b, p_b, c_n, p_n, frac, bool(ambiguous), text,
                    method, likelihood, int(sigma_dof))
