"""Are the diagnosis probabilities calibrated? (issue 15 item 2): a reliability table on generated sets.

Each generated set hides nothing or one effect of the vocabulary (equal chances) at a magnitude drawn between
"barely there" and the effect's usual test magnitude: the parameters of ``Effect.sample_truth`` moved towards
the effect's neutral value by a factor f ~ U(0.03, 0.6) in the optimizer's scaled coordinates (log10 for log
parameters). The protocol is sparse so that the probabilities are not all 0 or 1: 2 to 4 random test points,
1 to 3 random signed axis directions, no preload sweep, 3 trials, the case's noise and dial. Each set is
diagnosed (analytical detailed model, every single effect and pair weighed) and every explanation's posterior
probability is paired with whether it is the hidden one (explanation level), and every effect's marginal
probability (the sum over the explanations that contain it) with whether it is hidden (cause level).

The reliability table bins the predicted probabilities and gives, per bin, the number of predictions, their
mean and the observed frequency of being right, with a binomial standard error; ``ece`` is the expected
calibration error (count-weighted mean |observed - predicted|), ``brier`` the mean squared error.

``python -m femcheck.bench.calibration [--sets 60] [--jobs 2] [--seed 0] [--out reports/diagnose/calibration.md]``
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
    """One diagnosed set: ``hidden`` the hidden effect ids (empty = none), ``explanations`` [(ids, probability)],
    ``causes`` {effect id: marginal probability}, ``points``, ``directions``, ``seconds``."""

    seed: int
    hidden: tuple[str, ...]
    shrink: float
    points: tuple[str, ...]
    directions: tuple[str, ...]
    explanations: tuple
    causes: dict
    seconds: float


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


def one_set(seed: int, pairs: bool = False) -> GeneratedSet:
    """Generate, simulate and diagnose set ``seed`` (module docstring); ``pairs``: draw the hidden explanation from the
    diagnosis's size prior (none, single, pair 1/3 each) instead of none or one effect with equal chances."""
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
    if pairs:
        # the diagnosis's own prior (evidence.size_prior): none, a single, a pair with 1/3 each, uniform within
        size = int(rng.integers(3))
        picks = [] if size == 0 else sorted(rng.choice(len(pool), size=size, replace=False).tolist())
    else:
        pick = int(rng.integers(len(pool) + 1))
        picks = [] if pick == len(pool) else [pick]
    shrink = float(rng.uniform(0.03, 0.6))
    hidden = [(pool[i], shrunk_truth(get_effect(pool[i]), model, rng, case, shrink)) for i in picks]
    points = tuple(sorted(rng.choice(POINT_LABELS, size=int(rng.integers(2, 5)), replace=False).tolist()))
    directions = tuple(rng.choice(AXES, size=int(rng.integers(1, 4)), replace=False).tolist())
    ve = simulate(case, hidden, seed=seed, directions=directions, sweep=False)
    keep = np.isin(ve.data.point, points)
    data = dc.replace(ve.data, **{f: getattr(ve.data, f)[keep] for f in
                                  ("point", "direction", "trial", "phase", "load_N", "force", "disp", "row")})
    t0 = time.perf_counter()
    d = diagnose(model, process(data, case), with_baseline=False)
    w = d.weighing
    expl = tuple((tuple(sorted(e.ids)), float(p)) for e, p in zip(w.explanations, w.probability))
    causes = {c: float(sum(p for ids, p in expl if c in ids)) for c in pool}
    return GeneratedSet(seed=seed, hidden=tuple(h[0] for h in hidden), shrink=shrink, points=points,
                        directions=directions, explanations=expl, causes=causes, seconds=time.perf_counter() - t0)


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


def _one_set_pairs(seed: int) -> GeneratedSet:
    return one_set(seed, pairs=True)


def calibration(n_sets: int = 60, jobs: int = 1, seed: int = 0, pairs: bool = False) -> dict:
    """Generate and diagnose ``n_sets`` sets (seeds ``seed`` ..), return the explanation- and cause-level reliability
    tables, the sets and the wall time."""
    t0 = time.perf_counter()
    seeds = list(range(seed, seed + n_sets))
    if jobs > 1:
        from concurrent.futures import ProcessPoolExecutor
        with ProcessPoolExecutor(jobs) as ex:
            sets = list(ex.map(_one_set_pairs if pairs else one_set, seeds))
    else:
        sets = [one_set(s, pairs) for s in seeds]
    ep, er, cp, cr, top_p, top_r = [], [], [], [], [], []
    for s in sets:
        truth = tuple(sorted(s.hidden))
        for k, (ids, p) in enumerate(s.explanations):
            ep.append(p)
            er.append(ids == truth)
        lead = max(s.explanations, key=lambda t: t[1])
        top_p.append(lead[1])
        top_r.append(lead[0] == truth)
        for c, p in s.causes.items():
            cp.append(p)
            cr.append(c in s.hidden)
    return {"explanations": reliability(ep, er), "causes": reliability(cp, cr), "leader": reliability(top_p, top_r),
            "sets": sets, "n_sets": n_sets, "wall_s": time.perf_counter() - t0,
            "mean_diagnosis_s": float(np.mean([s.seconds for s in sets])) if sets else float("nan")}


def markdown(result: dict, command: str) -> str:
    """The reliability tables as Markdown, with the command that produced them."""
    out = [f"`{command}` ({result['n_sets']} sets, {result['wall_s']:.0f} s, mean diagnosis "
           f"{result['mean_diagnosis_s']:.1f} s)", ""]
    for key, title in (("explanations", "every explanation's posterior vs being the hidden one"),
                       ("causes", "every effect's marginal probability vs being hidden"),
                       ("leader", "the leading explanation's posterior vs being the hidden one")):
        r = result[key]
        out += [f"**{title}** ({r['n']} predictions; ECE {r['ece']:.3f}, Brier {r['brier']:.3f})", "",
                "| predicted | n | mean predicted | observed right | ± se |", "|---|---|---|---|---|"]
        for b in r["bins"]:
            if b["n"]:
                out.append(f"| {b['lo']:.1f}–{b['hi']:.1f} | {b['n']} | {b['mean_predicted']:.3f} | {b['observed']:.3f} | "
                           f"{b['observed_se']:.3f} |")
            else:
                out.append(f"| {b['lo']:.1f}–{b['hi']:.1f} | 0 | – | – | – |")
        out.append("")
    wrong = [(s, ids, p) for s in result["sets"] for ids, p in s.explanations
             if p >= 0.9 and ids != tuple(sorted(s.hidden))]
    if wrong:
        out += ["**explanations given >= 0.9 that were wrong**", "", "| set | hidden | shrink | points | directions | "
                "named | probability |", "|---|---|---|---|---|---|---|"]
        out += [f"| {s.seed} | {'+'.join(s.hidden) or 'none'} | {s.shrink:.2f} | {' '.join(s.points)} | "
                f"{' '.join(s.directions)} | {'+'.join(ids) or 'none'} | {p:.3f} |" for s, ids, p in wrong]
        out.append("")
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m femcheck.bench.calibration", description=__doc__.split("\n")[0])
    ap.add_argument("--sets", type=int, default=60)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="reports/diagnose/calibration.md")
    ap.add_argument("--pairs", action="store_true", help="hide none, one or two effects with the diagnosis's size prior "
                    "(1/3 each) instead of none or one effect")
    a = ap.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    res = calibration(a.sets, a.jobs, a.seed, a.pairs)
    cmd = f"python -m femcheck.bench.calibration --sets {a.sets} --jobs {a.jobs} --seed {a.seed}" + (" --pairs" if a.pairs else "")
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
