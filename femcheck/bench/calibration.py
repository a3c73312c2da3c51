"""Are the diagnosis probabilities calibrated? A reliability table on generated sets.

Two generators of hidden truths (``--truth``):

* ``prior`` (default): the diagnosis's own prior. The hidden explanation is drawn from the size prior of
  :func:`femcheck.diagnose.evidence.size_prior` (none, a single effect, a pair with 1/3 each, uniform within the
  size, over the applicable vocabulary) and each hidden effect's parameters from the parameter prior of
  :mod:`femcheck.diagnose.prior` (the prior the Laplace evidence integrates over; a located effect first draws its
  legs). If the evidence were exact, the posterior would then be calibrated by construction (Bayes' rule on the
  generating distribution); what the table measures is the error of the evidence approximation (Laplace or BIC),
  of the fits (local optima, warm starts) and of the noise model (sigma estimated from 3 trials, quantized dials);
* ``shrunk``: none or one effect (equal chances; ``--pairs``: the size prior), at a magnitude drawn between "barely
  there" and the effect's usual test magnitude: the parameters of ``Effect.sample_truth`` moved towards the effect's
  neutral value by a factor f ~ U(0.03, 0.6) in the optimizer's scaled coordinates (log10 for log parameters).
  This generator is *not* the evidence's prior; it tests robustness to a prior mismatch.

The protocol is sparse so that the probabilities are not all 0 or 1: 2 to 4 random test points, 1 to 3 random
signed axis directions, no preload sweep, 3 trials, the case's noise and dial. Each set is diagnosed (analytical
detailed model, every single effect and pair weighed) and, for each evidence approximation (``laplace`` and ``bic``,
weighed on the same fits), every explanation's posterior probability is paired with whether it is the hidden one
(explanation level), and every effect's marginal probability (the sum over the explanations that contain it) with
whether it is hidden (cause level). Each is done for both likelihoods (``gauss``: sigma known; ``student``: sigma
integrated out of its scatter estimate with ``sigma_dof`` dof, :func:`femcheck.diagnose.evidence.student_term`), also
on the same fits; ``sigma_dof`` of each set is kept (0 when the dial quantum sets sigma: both likelihoods then agree).

The reliability table bins the predicted probabilities and gives, per bin, the number of predictions, their
mean and the observed frequency of being right, with a binomial standard error; ``ece`` is the expected
calibration error (count-weighted mean |observed - predicted|), ``brier`` the mean squared error.

``python -m femcheck.bench.calibration [--sets 60] [--jobs 2] [--seed 0] [--truth prior|shrunk] [--pairs]
[--likelihood gauss|student] [--out reports/diagnose/calibration.md]``
"""
from __future__ import annotations

import argparse
import dataclasses
import logging
import time

import numpy as np

log = logging.getLogger(__name__)
CASE_PATH = "cases/haptic_6psu.toml"
BINS = (0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0 + 1e-12)
AXES = ("+x", "-x", "+y", "-y", "+z", "-z")


@dataclasses.dataclass(frozen=True)
class GeneratedSet:
    """One diagnosed set: ``hidden`` the hidden effect ids (empty = none), ``explanations`` [(ids, probability)] and
    ``causes`` {effect id: marginal probability} of the default evidence, ``by_method`` {method: explanations} for
    each evidence approximation, ``points``, ``directions``, ``seconds``."""

    seed: int
    hidden: tuple[str, ...]
    shrink: float
    points: tuple[str, ...]
    directions: tuple[str, ...]
    explanations: tuple
    causes: dict
    seconds: float
    by_method: dict = dataclasses.field(default_factory=dict)
    truth: tuple = ()
    #: degrees of freedom of the scatter estimate of sigma (``Readings.sigma_dof``; 0: the dial quantum sets it)
    sigma_dof: int = 0
    #: {likelihood: {method: explanations}} (``by_method`` is the entry of the weighing's likelihood)
    by_likelihood: dict = dataclasses.field(default_factory=dict)


def shrunk_truth(effect, model, rng, case, shrink: float) -> dict:
    """``effect.sample_truth`` moved towards the neutral value by ``shrink`` in scaled coordinates."""
    full = effect.values_from(effect.sample_truth(rng, case), model)
    neutral = effect.neutral(model)
    out = {}
    for p, v, n in zip(effect.params, full, neutral):
        if p.log and n <= 0:
            n = p.lower if p.lower > 0 else v
        x = p.to_x(n) + shrink * (p.to_x(v) - p.to_x(n))
        out[p.name] = float(np.clip(p.from_x(x), p.lower, p.upper))
    return out


def one_set(seed: int, pairs: bool = False, truth: str = "shrunk", max_located: int = 1,
            likelihood: str | None = None) -> GeneratedSet:
    """Generate, simulate and diagnose set ``seed`` (module docstring); ``truth`` "prior" | "shrunk"; ``pairs`` (shrunk
    only): draw the hidden explanation from the diagnosis's size prior (none, single, pair 1/3 each) instead of none
    or one effect with equal chances; ``max_located``: placements of located effects that join the rivals."""
    import dataclasses as dc

    import femcheck
    from femcheck.diagnose import AnalyticalChainModel, diagnose
    from femcheck.diagnose.effects import VOCABULARY, get_effect
    from femcheck.experiment.simulate import simulate
    from femcheck.kinematics.psu6 import POINT_LABELS
    from femcheck.measured import process

    case = femcheck.load_case(CASE_PATH)
    model = AnalyticalChainModel(case, "detailed", "rigid")
    rng = np.random.default_rng(10_000 + seed)
    pool = [e for e in VOCABULARY if e != "none" and get_effect(e).applicable(model)]
    if truth not in ("prior", "shrunk"):
        raise ValueError(f"truth: {truth!r}; expected prior or shrunk")
    if pairs or truth == "prior":
        # the diagnosis's own prior (evidence.size_prior): none, a single, a pair with 1/3 each, uniform within
        size = int(rng.integers(3))
        picks = [] if size == 0 else sorted(rng.choice(len(pool), size=size, replace=False).tolist())
    else:
        pick = int(rng.integers(len(pool) + 1))
        picks = [] if pick == len(pool) else [pick]
    if truth == "prior":
        from femcheck.diagnose.prior import draw_truth
        shrink = float("nan")
        hidden = [draw_truth(get_effect(pool[i]), model, rng) for i in picks]
    else:
        shrink = float(rng.uniform(0.03, 0.6))
        hidden = [(pool[i], shrunk_truth(get_effect(pool[i]), model, rng, case, shrink)) for i in picks]
    points = tuple(sorted(rng.choice(POINT_LABELS, size=int(rng.integers(2, 5)), replace=False).tolist()))
    directions = tuple(rng.choice(AXES, size=int(rng.integers(1, 4)), replace=False).tolist())
    ve = simulate(case, hidden, seed=seed, directions=directions, sweep=False)
    keep = np.isin(ve.data.point, points)
    data = dc.replace(ve.data, **{f: getattr(ve.data, f)[keep] for f in
                                  ("point", "direction", "trial", "phase", "load_N", "force", "disp", "row")})
    t0 = time.perf_counter()
    readings = process(data, case)
    d = diagnose(model, readings, with_baseline=False, max_located=max_located, likelihood=likelihood)
    seconds = time.perf_counter() - t0
    from femcheck.diagnose import evidence
    w = d.weighing
    by_likelihood = {}
    for lik in evidence.LIKELIHOODS:
        by_likelihood[lik] = {}
        for m in evidence.EVIDENCE_METHODS:
            p = evidence.posterior(w.explanations, w.n_data, m, lik, readings.sigma_dof)
            merged = {}   # an explanation is scored by its cause ids: the placements of one located cause are summed
            for e, q in zip(w.explanations, p):
                key = tuple(sorted(e.ids))
                merged[key] = merged.get(key, 0.0) + float(q)
            by_likelihood[lik][m] = tuple(merged.items())
    by_method = by_likelihood[w.likelihood]
    expl = by_method[w.method]
    causes = {c: float(sum(p for ids, p in expl if c in ids)) for c in pool}
    return GeneratedSet(seed=seed, hidden=tuple(h[0] for h in hidden), shrink=shrink, points=points,
                        directions=directions, explanations=expl, causes=causes, seconds=seconds, by_method=by_method,
                        sigma_dof=int(readings.sigma_dof), by_likelihood=by_likelihood,
                        truth=tuple((h[0], tuple(sorted(h[1].items()))) for h in hidden))


def reliability(predicted, right, bins=BINS) -> dict:
    """Reliability table of ``predicted`` probabilities (n,) against the outcomes ``right`` (n,) bool: per bin
    ``lo``, ``hi``, ``n``, ``mean_predicted``, ``observed``, ``observed_se``; plus ``ece`` and ``brier``."""
    p, y = np.asarray(predicted, float), np.asarray(right, float)
    rows = []
    for lo, hi in zip(bins[:-1], bins[1:]):
        m = (p >= lo) & (p < hi)
        n = int(m.sum())
        obs = float(y[m].mean()) if n else float("nan")
        rows.append({"lo": lo, "hi": min(hi, 1.0), "n": n, "mean_predicted": float(p[m].mean()) if n else float("nan"),
                     "observed": obs, "observed_se": float(np.sqrt(obs * (1 - obs) / n)) if n else float("nan")})
    ece = float(sum(r["n"] * abs(r["observed"] - r["mean_predicted"]) for r in rows if r["n"]) / max(len(p), 1))
    return {"bins": rows, "ece": ece, "brier": float(np.mean((p - y) ** 2)) if len(p) else float("nan"), "n": int(len(p))}


def _one_set_args(args) -> GeneratedSet:
    return one_set(*args)


def _tables(sets, key) -> dict:
    """Explanation-, cause- and leader-level reliability tables of ``sets`` for the explanations ``key(set)``."""
    ep, er, cp, cr, top_p, top_r = [], [], [], [], [], []
    for s in sets:
        truth = tuple(sorted(s.hidden))
        expl = key(s)
        for ids, p in expl:
            ep.append(p)
            er.append(ids == truth)
        lead = max(expl, key=lambda t: t[1])
        top_p.append(lead[1])
        top_r.append(lead[0] == truth)
        for c in s.causes:
            cp.append(float(sum(p for ids, p in expl if c in ids)))
            cr.append(c in s.hidden)
    return {"explanations": reliability(ep, er), "causes": reliability(cp, cr), "leader": reliability(top_p, top_r)}


def hides_located(s: GeneratedSet) -> bool:
    """Whether set ``s`` hides a located (``<element>_in_legs``) effect."""
    from femcheck.diagnose.effects import get_effect
    return any(get_effect(h).located for h in s.hidden)


def ece_null(predicted, n_draws: int = 1000, seed: int = 0) -> np.ndarray:
    """(n_draws,) ECE of ``predicted`` probabilities (n,) against outcomes drawn as Bernoulli(predicted): the
    sampling distribution of the ECE of a *perfectly calibrated* predictor with the same predictions (consistency
    resampling, Broecker & Smith, Weather Forecast. 22 (2007) 651). A few hundred predictions in a handful of bins
    give a calibrated predictor an ECE well above 0; an observed ECE is a finding only beyond this distribution."""
    p = np.asarray(predicted, float)
    rng = np.random.default_rng(seed)
    return np.array([reliability(p, rng.uniform(size=p.size) < p)["ece"] for _ in range(n_draws)])


def located_split(sets, key) -> dict:
    """Cause-level reliability on the sets that hide a located effect and on the others, and over all sets for the
    located causes (``<element>_in_legs``) and for the others, each with the 95 % quantile of the ECE a perfectly
    calibrated predictor would show on the same predictions (:func:`ece_null`) and the p-value of the observed ECE
    (flat keys).

    The split by *set* conditions on the hidden truth: on sets that hide a located effect, located causes are right
    more often than on average by construction, so even exact posteriors look under-confident there and
    over-confident on the other sets. The split by *cause* conditions on the prediction only, which calibration
    allows; it is the one to read."""
    from femcheck.diagnose.effects import get_effect
    out, rows = {}, [(min(1.0, float(sum(p for ids, p in key(s) if c in ids))), c in s.hidden,
                      bool(get_effect(c).located)) for s in sets for c in s.causes]
    p = np.array([r[0] for r in rows], float)
    y, k = (np.array([r[i] for r in rows], bool) for i in (1, 2))
    for tag, m in (("all_causes", np.ones(p.size, bool)), ("located_causes", k), ("other_causes", ~k)):
        r = reliability(p[m], y[m])
        null = ece_null(p[m]) if m.any() else np.array([np.nan])
        out[f"cause_ece_{tag}"] = r["ece"]
        out[f"cause_ece_null95_{tag}"] = float(np.quantile(null, 0.95))
        out[f"cause_ece_p_value_{tag}"] = float(np.mean(null >= r["ece"]))
        out[f"cause_table_{tag}"] = r
    for tag, sub in (("located_sets", [s for s in sets if hides_located(s)]),
                     ("other_sets", [s for s in sets if not hides_located(s)])):
        r = _tables(sub, key)["causes"] if sub else reliability([], [])
        out[f"cause_ece_{tag}"] = r["ece"]
        out[f"cause_brier_{tag}"] = r["brier"]
        out[f"n_sets_{tag}"] = len(sub)
        out[f"cause_table_{tag}"] = r
    return out


def calibration(n_sets: int = 60, jobs: int = 1, seed: int = 0, pairs: bool = False, truth: str = "shrunk",
                max_located: int = 1, likelihood: str | None = None) -> dict:
    """Generate and diagnose ``n_sets`` sets (seeds ``seed`` ..), return the explanation- and cause-level reliability
    tables of the default evidence (top level), of each approximation (``by_method``) and of each likelihood and
    approximation (``by_likelihood``), the share of sets with sigma from the trial scatter
    (``sigma_dof_positive_fraction``), the sets and the wall time."""
    from femcheck.diagnose import evidence
    t0 = time.perf_counter()
    args = [(s, pairs, truth, max_located, likelihood) for s in range(seed, seed + n_sets)]
    if jobs > 1:
        from concurrent.futures import ProcessPoolExecutor
        with ProcessPoolExecutor(jobs) as ex:
            sets = list(ex.map(_one_set_args, args))
    else:
        sets = [one_set(*a) for a in args]
    out = _tables(sets, lambda s: s.explanations)
    out["by_method"] = {m: _tables(sets, lambda s, m=m: s.by_method[m]) for m in evidence.EVIDENCE_METHODS}
    out["by_likelihood"] = {lik: {m: _tables(sets, lambda s, m=m, lik=lik: s.by_likelihood[lik][m])
                                  for m in evidence.EVIDENCE_METHODS} for lik in evidence.LIKELIHOODS}
    out["sigma_dof_positive_fraction"] = float(np.mean([s.sigma_dof > 0 for s in sets])) if sets else float("nan")
    for m in evidence.EVIDENCE_METHODS:
        out["by_method"][m].update(located_split(sets, lambda s, m=m: s.by_method[m]))
    out.update(sets=sets, n_sets=n_sets, wall_s=time.perf_counter() - t0, default_method=evidence.EVIDENCE,
               likelihood=likelihood or evidence.LIKELIHOOD,
               mean_diagnosis_s=float(np.mean([s.seconds for s in sets])) if sets else float("nan"))
    return out


def markdown(result: dict, command: str) -> str:
    """The reliability tables as Markdown, with the command that produced them."""
    out = [f"`{command}` ({result['n_sets']} sets, {result['wall_s']:.0f} s, mean diagnosis "
           f"{result['mean_diagnosis_s']:.1f} s; default evidence {result['default_method']}, likelihood "
           f"{result.get('likelihood', 'gauss')})", "",
           "| evidence | explanation ECE | explanation Brier | cause ECE | cause Brier | leader ECE |", "|---|---|---|---|---|---|"]
    for m, t in result["by_method"].items():
        out.append(f"| {m} | {t['explanations']['ece']:.4f} | {t['explanations']['brier']:.4f} | {t['causes']['ece']:.4f} | "
                   f"{t['causes']['brier']:.4f} | {t['leader']['ece']:.4f} |")
    out += ["", "| evidence | cause ECE, sets hiding a located effect | cause ECE, the others |", "|---|---|---|"]
    for m, t in result["by_method"].items():
        out.append(f"| {m} | {t['cause_ece_located_sets']:.4f} ({t['n_sets_located_sets']} sets) | "
                   f"{t['cause_ece_other_sets']:.4f} ({t['n_sets_other_sets']} sets) |")
    out += ["", "| evidence | causes | cause ECE | ECE of a calibrated predictor, 95 % | p-value |", "|---|---|---|---|---|"]
    for m, t in result["by_method"].items():
        for tag, title in (("all_causes", "all"), ("located_causes", "located"), ("other_causes", "the others")):
            out.append(f"| {m} | {title} ({t[f'cause_table_{tag}']['n']} predictions) | {t[f'cause_ece_{tag}']:.4f} | "
                       f"{t[f'cause_ece_null95_{tag}']:.4f} | {t[f'cause_ece_p_value_{tag}']:.2f} |")
    out.append("")
    if "by_likelihood" in result:
        out += [f"sigma from the trial scatter (sigma_dof > 0) on {result['sigma_dof_positive_fraction']:.0%} of the "
                "sets; elsewhere the dial quantum sets sigma and both likelihoods agree", "",
                "| evidence | likelihood | explanation ECE | explanation Brier | cause ECE | cause Brier | leader ECE |",
                "|---|---|---|---|---|---|---|"]
        for lik, by in result["by_likelihood"].items():
            for m, t in by.items():
                out.append(f"| {m} | {lik} | {t['explanations']['ece']:.4f} | {t['explanations']['brier']:.4f} | "
                           f"{t['causes']['ece']:.4f} | {t['causes']['brier']:.4f} | {t['leader']['ece']:.4f} |")
        out.append("")
    for m, t in result["by_method"].items():
        out += _markdown_tables(t, f" ({m})")
        for tag, title in (("located_causes", "located causes"), ("other_causes", "the other causes"),
                           ("located_sets", "sets hiding a located effect"), ("other_sets", "the other sets")):
            out += _markdown_tables({"causes": t[f"cause_table_{tag}"]}, f" ({m}, {title})", keys=("causes",))
    return "\n".join(out + _markdown_wrong(result))


def _markdown_tables(result: dict, tag: str, keys=("explanations", "causes", "leader")) -> list:
    out = []
    for key, title in (("explanations", "every explanation's posterior vs being the hidden one"),
                       ("causes", "every effect's marginal probability vs being hidden"),
                       ("leader", "the leading explanation's posterior vs being the hidden one")):
        if key not in keys:
            continue
        r = result[key]
        out += [f"**{title}{tag}** ({r['n']} predictions; ECE {r['ece']:.3f}, Brier {r['brier']:.3f})", "",
                "| predicted | n | mean predicted | observed right | ± se |", "|---|---|---|---|---|"]
        for b in r["bins"]:
            if b["n"]:
                out.append(f"| {b['lo']:.1f}–{b['hi']:.1f} | {b['n']} | {b['mean_predicted']:.3f} | {b['observed']:.3f} | "
                           f"{b['observed_se']:.3f} |")
            else:
                out.append(f"| {b['lo']:.1f}–{b['hi']:.1f} | 0 | – | – | – |")
        out.append("")
    return out


def _markdown_wrong(result: dict) -> list:
    out = []
    wrong = [(s, ids, p) for s in result["sets"] for ids, p in s.explanations
             if p >= 0.9 and ids != tuple(sorted(s.hidden))]
    if wrong:
        out += ["**explanations given >= 0.9 that were wrong**", "", "| set | hidden | shrink | points | directions | "
                "named | probability |", "|---|---|---|---|---|---|---|"]
        out += [f"| {s.seed} | {'+'.join(s.hidden) or 'none'} | {s.shrink:.2f} | {' '.join(s.points)} | "
                f"{' '.join(s.directions)} | {'+'.join(ids) or 'none'} | {p:.3f} |" for s, ids, p in wrong]
        out.append("")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m femcheck.bench.calibration", description=__doc__.split("\n")[0])
    ap.add_argument("--sets", type=int, default=60)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="reports/diagnose/calibration.md")
    ap.add_argument("--pairs", action="store_true", help="(--truth shrunk) hide none, one or two effects with the "
                    "diagnosis's size prior (1/3 each) instead of none or one effect")
    ap.add_argument("--truth", choices=("prior", "shrunk"), default="prior",
                    help="draw the hidden truths from the evidence's prior (default) or shrink Effect.sample_truth")
    ap.add_argument("--max-located", type=int, default=1, help="placements of located effects weighed (diagnose's "
                    "max_located)")
    ap.add_argument("--likelihood", choices=("gauss", "student"), default=None,
                    help="likelihood of the diagnosis's own weighing (default femcheck.diagnose.evidence.LIKELIHOOD); "
                         "both are tabulated from the same fits")
    a = ap.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    res = calibration(a.sets, a.jobs, a.seed, a.pairs, a.truth, a.max_located, a.likelihood)
    cmd = (f"python -m femcheck.bench.calibration --sets {a.sets} --jobs {a.jobs} --seed {a.seed} --truth {a.truth}"
           + (" --pairs" if a.pairs else "") + (f" --max-located {a.max_located}" if a.max_located != 1 else "")
           + (f" --likelihood {a.likelihood}" if a.likelihood else ""))
    text = markdown(res, cmd)
    from femcheck.report.atomic import write_text_atomic
    write_text_atomic(a.out, text + "\n")
    import json
    write_text_atomic(a.out.rsplit(".", 1)[0] + ".json", json.dumps(
        [dataclasses.asdict(st) for st in res["sets"]], indent=0, default=float))
    print(text)
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
