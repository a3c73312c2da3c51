"""The hidden-effect matrix (issue 7 acceptance): simulate the protocol with one hidden effect of random
magnitude and location (``Effect.sample_truth``) plus noise, diagnose it against the detailed ``rigid``
model, and tabulate which cause is named (confusion matrix) and how much the held-out error drops.

``python -m femcheck.bench.hidden_effects [--seeds N] [--jobs J] [--out reports/diagnose/confusion.md]``
runs the full matrix (every vocabulary id x N seeds) and writes the Markdown confusion matrix.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import time

import numpy as np

from femcheck.diagnose.effects import VOCABULARY, get_effect

log = logging.getLogger(__name__)
CASE_PATH = "cases/haptic_6psu.toml"


@dataclasses.dataclass(frozen=True)
class MatrixCase:
    hidden: str
    seed: int
    truth: dict
    named: tuple[str, ...]
    location: str
    location_match: bool | None
    error_before: float
    error_after: float
    significant: bool
    seconds: float

    @property
    def match(self) -> bool:
        return self.named[:1] == (self.hidden,)

    @property
    def drop(self) -> float:
        """Relative drop of the overall held-out error (1 - after / before)."""
        return 1.0 - self.error_after / self.error_before


def _location_match(hidden: str, truth_params: dict, diag, diag_model=None) -> bool | None:
    if not diag.causes or diag.causes[0].id != hidden:
        return None
    c = diag.causes[0]
    eff = get_effect(hidden)
    if hidden == "leg_softening":
        true = sorted(int(k[3:]) for k, v in truth_params.items() if v > 1.0)
        lo = np.array([c.params_ci[f"leg{i}"][0] for i in range(6)])
        return eff.soft_legs(None, lo) == true
    if eff.located:   # the named legs are exactly the hidden ones
        return list(c.legs) == eff.truth_legs(truth_params, diag_model)
    if hidden == "clearance":
        true = [a for a in "xyz" if truth_params[f"gap_{a}_m"] > 0]
        lo = np.array([c.params_ci[f"gap_{a}_m"][0] for a in "xyz"])
        return eff.gapped_axes(None, lo) == true
    return None


def run_case(case, hidden: str, seed: int, directions=None) -> MatrixCase:
    """Simulate one hidden effect (random magnitude/location from ``seed``) and diagnose it."""
    from femcheck.diagnose import AnalyticalChainModel, diagnose
    from femcheck.experiment.simulate import ALL_DIRECTIONS, simulate
    from femcheck.measured import process

    model = AnalyticalChainModel(case, "detailed", "rigid")
    if hidden != "none" and not get_effect(hidden).applicable(model):
        model = AnalyticalChainModel(case, "simplified", "rigid")   # an effect that adds what the model lacks
    ve = simulate(case, [] if hidden == "none" else [(hidden, {})], seed=seed, directions=directions or ALL_DIRECTIONS,
                  level=model.level)
    readings = process(ve.data, case)
    t = time.perf_counter()
    d = diagnose(model, readings, with_baseline=False)
    truth = ve.truth["effects"][0]
    return MatrixCase(hidden=hidden, seed=seed, truth=truth["params"], named=tuple(c.id for c in d.causes),
                      location=d.causes[0].location, location_match=_location_match(hidden, truth["params"], d, model),
                      error_before=d.heldout_error_before["overall"], error_after=d.heldout_error_after["overall"],
                      significant=d.significant, seconds=time.perf_counter() - t)


def _run(args):
    from femcheck.case import load_case
    hidden, seed = args
    r = run_case(load_case(CASE_PATH), hidden, seed)
    log.info("%s seed %d -> %s (error %.3f -> %.3f, %.1f s)", hidden, seed, "+".join(r.named), r.error_before,
             r.error_after, r.seconds)
    return r


def run_matrix(ids=VOCABULARY, seeds=range(10), jobs: int = 1) -> list[MatrixCase]:
    """Every id in ``ids`` x every seed offset in ``seeds`` (seed = 1000 (vocabulary index + 1) + offset)."""
    tasks = [(h, 1000 * (VOCABULARY.index(h) + 1) + s) for h in ids for s in seeds]
    if jobs > 1:
        from concurrent.futures import ProcessPoolExecutor
        with ProcessPoolExecutor(max_workers=jobs) as ex:
            return list(ex.map(_run, tasks))
    return [_run(t) for t in tasks]


def confusion_markdown(results: list[MatrixCase]) -> str:
    """Confusion matrix (rows: hidden, columns: first named cause) and per-id rates as Markdown."""
    ids = list(dict.fromkeys(r.hidden for r in results))
    cols = list(dict.fromkeys(ids + [r.named[0] for r in results]))
    lines = ["| hidden \\ named | " + " | ".join(cols) + " | match % | 2nd cause named % | drop >= 50 % | "
             "median drop % | location match |", "|" + "---|" * (len(cols) + 6)]
    for h in ids:
        rs = [r for r in results if r.hidden == h]
        counts = [sum(r.named[0] == c for r in rs) for c in cols]
        loc = [r.location_match for r in rs if r.location_match is not None]
        drop_ok = "-" if h == "none" else f"{sum(r.drop >= 0.5 for r in rs)}/{len(rs)}"
        med = "-" if h == "none" else f"{100 * np.median([r.drop for r in rs]):.0f}"
        lines.append(f"| **{h}** | " + " | ".join(str(c) if c else "." for c in counts)
                     + f" | {100 * np.mean([r.match for r in rs]):.0f} | {100 * np.mean([len(r.named) > 1 for r in rs]):.0f}"
                     + f" | {drop_ok} | {med} | {f'{sum(loc)}/{len(loc)}' if loc else '-'} |")
    n = len(results)
    tot = sum(r.match for r in results)
    lines += ["", f"{tot}/{n} cases ({100 * tot / n:.1f} %) name the hidden cause first; "
              f"mean diagnosis time {np.mean([r.seconds for r in results]):.1f} s per case."]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--ids", default=",".join(VOCABULARY))
    ap.add_argument("--out", default="reports/diagnose/confusion.md")
    a = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    logging.getLogger("femcheck.diagnose.selection").setLevel(logging.WARNING)
    logging.getLogger("femcheck.diagnose.fitting").setLevel(logging.WARNING)
    t = time.perf_counter()
    res = run_matrix(a.ids.split(","), range(a.seeds), a.jobs)
    md = (f"# Hidden-effect matrix: {len(res)} virtual experiments ({a.seeds} seeds per id), diagnosed against "
          f"the detailed rigid model\n\n" + confusion_markdown(res)
          + f"\n\nWall time {time.perf_counter() - t:.0f} s with {a.jobs} process(es). Generated by "
          f"`python -m femcheck.bench.hidden_effects --seeds {a.seeds}`.\n")
    from femcheck.report.atomic import write_text_atomic
    write_text_atomic(a.out, md)
    write_text_atomic(a.out.rsplit(".", 1)[0] + ".json", json.dumps([dataclasses.asdict(r) | {"match": r.match, "drop": r.drop}
                                                                    for r in res], indent=1, default=float))
    print(md)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
