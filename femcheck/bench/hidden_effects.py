"""The hidden-effect matrix: simulate the protocol with one hidden effect of random
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


# --- data that do not come from the fitted model family -------------------------------------------

#: hidden effects that the device FE world can carry: they act on the force or the reading, not on an element scale
FE_HIDDEN = ("none", "clearance", "friction_hysteresis", "sensor_misalignment")
WORLDS = ("same_model", "noise_6um", "foreign", "fe_released", "fe_simplified")
_FE_MODEL = None   # the device FE reading model of the FE worlds (built once, inherited by forked workers)


@dataclasses.dataclass(frozen=True)
class WorldCase:
    """One dataset of a world: ``hidden`` its hidden cause, ``named`` the causes named, ``verdict``, ``right``
    whether the answer is the expected one (see :func:`run_world_case`), ``seconds`` of diagnosis."""

    world: str
    hidden: str
    seed: int
    named: tuple[str, ...]
    verdict: str
    right: bool
    seconds: float
    #: goodness of fit of the named explanation: overall chi^2 / dof and p, and the structured lack-of-fit p
    chi2_per_dof: float = float("nan")
    p_value: float = float("nan")
    lack_of_fit_p_value: float = float("nan")


def run_world_case(case, world: str, hidden: str, seed: int, directions=("+x", "+y", "+z")) -> WorldCase:
    """Simulate one dataset of ``world`` and diagnose it. Worlds and what counts as right:

    * ``same_model``: the analytical model with one vocabulary effect (random magnitude and place, the case's
      noise), diagnosed against the same model level: the first named cause is the hidden one (``none``: nothing
      named);
    * ``noise_6um``: the same with 6 um reading noise (twice the case's);
    * ``foreign``: an out-of-vocabulary effect (:mod:`femcheck.experiment.foreign`; ``hidden`` = ``name@magnitude``,
      magnitude 0.1 when not given) on the analytical model: the verdict is ``unexplained``;
    * ``fe_released``: the device FE with frictional contact joints (``--model fe``) as the world, with one of
      :data:`FE_HIDDEN` on top, diagnosed against the analytical detailed model with ``released`` joints (its closest
      analytical idealization): the hidden cause is named (first or second; the FE's own secant Hertz law against
      the model's tangent is a real second cause, ``hertz_stiffening``), ``none``: no cause other than that;
    * ``fe_simplified``: the FE world with nothing hidden, diagnosed against the simplified model (the paper's
      storyline): ``missing_compliance`` is named first.
    """
    from femcheck.diagnose import AnalyticalChainModel, diagnose
    from femcheck.experiment.simulate import simulate
    from femcheck.measured import process

    hid = [] if hidden == "none" else [(hidden, {})]
    if world in ("same_model", "noise_6um"):
        model = AnalyticalChainModel(case, "detailed", "rigid")
        if hid and not get_effect(hidden).applicable(model):
            model = AnalyticalChainModel(case, "simplified", "rigid")
        ve = simulate(case, hid, seed=seed, directions=directions, level=model.level,
                      noise_sigma_m=6e-6 if world == "noise_6um" else None)
    elif world == "foreign":
        from femcheck.experiment.foreign import simulate_foreign
        model = AnalyticalChainModel(case, "detailed", "rigid")
        name, _, mag = hidden.partition("@")       # "base_rocking@0.2": effect and magnitude (default 0.1)
        ve = simulate_foreign(case, name, float(mag or 0.1), seed=seed, directions=directions)
    elif world in ("fe_released", "fe_simplified"):
        if _FE_MODEL is None:
            raise RuntimeError("the FE worlds need set_fe_world() first")
        model = AnalyticalChainModel(case, "detailed" if world == "fe_released" else "simplified",
                                     "released" if world == "fe_released" else "rigid")
        ve = simulate(case, hid, seed=seed, directions=directions, model=_FE_MODEL)
    else:
        raise ValueError(f"unknown world {world!r}; expected one of {', '.join(WORLDS)}")
    r = process(ve.data, case)
    t = time.perf_counter()
    d = diagnose(model, r, with_baseline=False)
    named = tuple(c.id for c in d.causes)
    if world in ("same_model", "noise_6um"):
        right = named[:1] == (hidden,)
    elif world == "foreign":
        right = d.verdict == "unexplained"
    elif world == "fe_released":
        right = set(named) <= {"none", "hertz_stiffening"} if hidden == "none" else hidden in named
    else:
        right = named[:1] == ("missing_compliance",)
    lof = d.lack_of_fit
    return WorldCase(world, hidden, seed, named, d.verdict, bool(right), time.perf_counter() - t,
                     d.weighing.chi2_per_dof, d.weighing.p_value, lof.p_value if lof is not None else float("nan"))


def set_fe_world(case, mesh: str = "coarse", parts: str = "solid"):
    """Build the device FE reading model of the FE worlds (``run_fe`` at P0..P8, detailed level, contact joints)."""
    global _FE_MODEL
    from femcheck.diagnose.fe_model import DeviceFEReadingModel
    from femcheck.kinematics.psu6 import POINT_LABELS
    from femcheck.verify.fe import run_fe
    _FE_MODEL = DeviceFEReadingModel(case, run_fe(case, POINT_LABELS, ("detailed",), mesh, jobs=1, kind=parts))
    return _FE_MODEL


def world_tasks(seeds: int = 1, magnitudes=(0.1,)) -> list[tuple[str, str, int]]:
    """(world, hidden, seed) of every dataset: each vocabulary id per seed in the analytical worlds, each foreign
    effect at each of ``magnitudes`` (hidden ``name@magnitude``), each FE-world hidden effect, and the FE storyline."""
    from femcheck.experiment.foreign import FOREIGN
    out = []
    for s in range(seeds):
        out += [(w, h, 3000 + 100 * s + VOCABULARY.index(h)) for w in ("same_model", "noise_6um") for h in VOCABULARY]
        out += [("foreign", f"{f}@{m:g}", 4000 + 100 * s + 10 * j + k) for j, m in enumerate(magnitudes)
                for k, f in enumerate(FOREIGN)]
        out += [("fe_released", h, 5000 + 100 * s + k) for k, h in enumerate(FE_HIDDEN)]
        out.append(("fe_simplified", "none", 6000 + s))
    return out


def _run_world(task):
    from femcheck.case import load_case
    w, h, seed = task
    r = run_world_case(load_case(CASE_PATH), w, h, seed)
    log.info("%s %s seed %d -> %s, %s (%s, %.1f s; chi2/dof %.2f p %.2g, lack of fit p %.2g)", w, h, seed,
             "+".join(r.named), r.verdict, "right" if r.right else "WRONG", r.seconds, r.chi2_per_dof, r.p_value,
             r.lack_of_fit_p_value)
    return r


def world_markdown(results: list[WorldCase]) -> str:
    """Per world: confusion matrix (rows hidden, columns first named cause), verdict counts and the right rate."""
    lines = []
    for w in dict.fromkeys(r.world for r in results):
        rs = [r for r in results if r.world == w]
        cols = list(dict.fromkeys(r.named[0] for r in rs))
        lines += [f"**{w}** ({len(rs)} sets; right: {sum(r.right for r in rs)}/{len(rs)}; unexplained: "
                  f"{sum(r.verdict == 'unexplained' for r in rs)}/{len(rs)})", "",
                  "| hidden \\ named first | " + " | ".join(cols) + " | none / explained / unexplained | right |",
                  "|" + "---|" * (len(cols) + 3)]
        for h in dict.fromkeys(r.hidden for r in rs):
            hr = [r for r in rs if r.hidden == h]
            v = [sum(r.verdict == k for r in hr) for k in ("none", "explained", "unexplained")]
            lines.append(f"| {h} | " + " | ".join(str(c) if (c := sum(r.named[0] == col for r in hr)) else "."
                                                  for col in cols)
                         + f" | {v[0]} / {v[1]} / {v[2]} | {sum(r.right for r in hr)}/{len(hr)} |")
        lines.append("")
    return "\n".join(lines)


def run_worlds(seeds: int = 1, jobs: int = 1, mesh: str = "coarse", parts: str = "solid", worlds=WORLDS,
               magnitudes=(0.1,)):
    """Every dataset of :func:`world_tasks` in ``worlds`` (the FE model is built once, before the workers fork)."""
    from femcheck.case import load_case
    tasks = [t for t in world_tasks(seeds, magnitudes) if t[0] in worlds]
    if any(t[0].startswith("fe_") for t in tasks):
        set_fe_world(load_case(CASE_PATH), mesh, parts)
    if jobs > 1:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor
        with ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("fork")) as ex:
            return list(ex.map(_run_world, tasks))
    return [_run_world(t) for t in tasks]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--ids", default=",".join(VOCABULARY))
    ap.add_argument("--out", default="reports/diagnose/confusion.md")
    ap.add_argument("--worlds", default=None, help="instead of the matrix: data from other worlds (comma list of "
                    f"{', '.join(WORLDS)}, or 'all'), --seeds sets per hidden effect")
    ap.add_argument("--mesh", default="coarse", help="FE worlds: mesh level")
    ap.add_argument("--parts", default="solid", help="FE worlds: solid | beam parts")
    ap.add_argument("--foreign-magnitudes", default="0.1", help="foreign world: comma list of magnitudes per effect")
    a = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    logging.getLogger("femcheck.diagnose.selection").setLevel(logging.WARNING)
    logging.getLogger("femcheck.diagnose.fitting").setLevel(logging.WARNING)
    t = time.perf_counter()
    if a.worlds:
        worlds = WORLDS if a.worlds == "all" else tuple(a.worlds.split(","))
        mags = tuple(float(m) for m in a.foreign_magnitudes.split(","))
        res = run_worlds(a.seeds, a.jobs, a.mesh, a.parts, worlds, mags)
        md = (f"# Diagnosis on data inside and outside the fitted model family ({len(res)} sets)\n\n"
              + world_markdown(res) + f"\nWall time {time.perf_counter() - t:.0f} s with {a.jobs} process(es); mean "
              f"diagnosis {np.mean([r.seconds for r in res]):.1f} s. Generated by `python -m femcheck.bench.hidden_effects "
              f"--worlds {a.worlds} --seeds {a.seeds} --jobs {a.jobs} --mesh {a.mesh} --parts {a.parts} "
              f"--foreign-magnitudes {a.foreign_magnitudes}`.\n")
        from femcheck.report.atomic import write_text_atomic
        write_text_atomic(a.out, md)
        write_text_atomic(a.out.rsplit(".", 1)[0] + ".json", json.dumps([dataclasses.asdict(r) for r in res], indent=1,
                                                                        default=float))
        print(md)
        return 0
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
