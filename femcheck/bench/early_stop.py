"""Bench area ``early_stop``: are the early stops of the rival pair fits safe?

The all-pairs diagnosis stops a pair fit that cannot come within chi^2 ``HOPELESS`` (40) of the leader
(:func:`femcheck.diagnose.selection.fit_rivals`, the greedy round's ``stop``): at its start when the Gauss-Newton floor
linearized there exceeds ``START_FACTOR`` x the threshold ``stop_above``, else after a ``PROBE_NFEV`` probe when the
floor there exceeds the threshold (:func:`femcheck.diagnose.fitting.fit_effects`); a floor is believed only where the
full Gauss-Newton step's gain ratio is within ``RHO_TOL`` of 1 (opt-in; off as shipped), and a pair whose nested
single is already within the threshold is never stopped (``nested_chi2``). The floor is the exact minimum only of the linearized problem; this area
measures, on generated variety, whether a stopped start's end-to-end fit (continued to convergence) is indeed beyond
the threshold.

Sets (seed s, generator :func:`generated_set`): the hidden explanation drawn from the diagnosis's own prior (none, a
single or a pair with 1/3 each, located effects with their legs; :func:`femcheck.diagnose.prior.draw_truth`), one set
in four with an out-of-vocabulary effect on top (:mod:`femcheck.experiment.foreign`, magnitude U(0.05, 0.2)), one in
four on the full protocol (9 points, +x +y +z, preload sweep), the others sparse (2 to 4 points, 1 to 3 signed
axes, no sweep), the case's reading noise (3 um) or twice it (6 um) alternately. Each set is diagnosed twice with
every pair weighed: with the stops as shipped and with every start fitted to the end
(:func:`femcheck.diagnose.fitting.early_stop_rules`, which audits the rules instead of applying them).

Figures (flat keys): ``sets``; ``pairs_stopped_at_start`` / ``pairs_stopped_after_probe`` (starts stopped in the
shipped runs); ``violations`` (audited starts the rules stop whose end-to-end chi^2 is within the threshold);
``max_abs_posterior_diff`` over every explanation, both evidence approximations; ``verdict_changes``,
``causes_changes``; ``cpu_with_stops_s``, ``cpu_without_stops_s`` and their ratio; ``floor_overshoot_max`` the
largest floor at start / end-to-end chi^2 over all audited starts (the nonlinearity the factor must cover);
``start_factor_critical``: the smallest START_FACTOR with no start-rule violation on these sets (the largest floor at
start / threshold among starts that end within it and pass the gain-ratio check) and ``start_factor_margin`` =
START_FACTOR / it; per factor f of ``FACTORS`` (key suffix ``_f1p5`` for 1.5) and per gain-ratio tolerance of ``RHO_TOLS``
(``_rho0p25``) the violations and the share of pair-fit residual evaluations saved (``evals_saved_frac``; evaluations,
not seconds: a pair's cost is its evaluations); the audits of the runs without the stops carry the gain ratios, so
every variant is measured on the same fits. The
audited starts are those of fits the nested bound leaves open to a stop (the exempt ones are fitted as without a
threshold in both runs).

``python -m femcheck.bench early_stop`` (``SETS`` sets) or ``python -m femcheck.bench.early_stop --sets N [--seed S]``
(writes reports/bench/early_stop.json).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import time

import numpy as np

AREA = "early_stop"
SETS = 24
FACTORS = (1.0, 1.25, 1.5, 2.0, 3.0)
RHO_TOLS = (0.1, 0.25, 0.5, 1.0)
CASE_PATH = "cases/haptic_6psu.toml"
AXES = ("+x", "-x", "+y", "-y", "+z", "-z")
FULL_DIRS = ("+x", "+y", "+z")


@dataclasses.dataclass(frozen=True)
class SetComparison:
    """One set diagnosed with and without the early stops: ``audits_on`` / ``audits_off`` the
    :class:`~femcheck.diagnose.fitting.StopAudit` of every pair start, ``posterior_diff`` the largest |p_on - p_off|
    over the explanations and both evidence approximations, CPU seconds of both runs."""

    seed: int
    label: str
    audits_on: tuple
    audits_off: tuple
    posterior_diff: float
    verdict_same: bool
    causes_same: bool
    cpu_on_s: float
    cpu_off_s: float


def generated_set(seed: int, *, sparse_only: bool = False):
    """(model, readings, label) of generated set ``seed`` (module docstring); ``sparse_only``: always the sparse
    protocol (the fast test)."""
    import dataclasses as dc

    import femcheck
    from femcheck.diagnose import AnalyticalChainModel
    from femcheck.diagnose.effects import VOCABULARY, get_effect
    from femcheck.diagnose.prior import draw_truth
    from femcheck.experiment.foreign import FOREIGN, simulate_foreign
    from femcheck.experiment.simulate import simulate
    from femcheck.kinematics.psu6 import POINT_LABELS
    from femcheck.measured import process

    case = femcheck.load_case(CASE_PATH)
    model = AnalyticalChainModel(case, "detailed", "rigid")
    rng = np.random.default_rng(20_000 + seed)
    pool = [e for e in VOCABULARY if e != "none" and get_effect(e).applicable(model)]
    size = int(rng.integers(3))
    picks = [] if size == 0 else sorted(rng.choice(len(pool), size=size, replace=False).tolist())
    hidden = [draw_truth(get_effect(pool[i]), model, rng) for i in picks]
    full = not sparse_only and seed % 4 == 3
    noise = 6e-6 if seed % 2 else None
    foreign = FOREIGN[int(rng.integers(len(FOREIGN)))] if seed % 4 == 1 else None
    mag = float(rng.uniform(0.05, 0.2))
    if full:
        points, directions = tuple(POINT_LABELS), FULL_DIRS
    else:
        points = tuple(sorted(rng.choice(POINT_LABELS, size=int(rng.integers(2, 5)), replace=False).tolist()))
        directions = tuple(rng.choice(AXES, size=int(rng.integers(1, 4)), replace=False).tolist())
    if foreign:
        ve = simulate_foreign(case, foreign, mag, hidden=hidden, seed=seed, directions=directions, noise_sigma_m=noise)
    else:
        ve = simulate(case, hidden, seed=seed, directions=directions, sweep=full, noise_sigma_m=noise)
    data = ve.data
    if not full:
        keep = np.isin(data.point, points)
        data = dc.replace(data, **{f: getattr(data, f)[keep] for f in
                                   ("point", "direction", "trial", "phase", "load_N", "force", "disp", "row")})
    label = (f"{'+'.join(h[0] for h in hidden) or 'none'}{'+' + foreign if foreign else ''} "
             f"{'full' if full else 'sparse'} {len(points)}pt {''.join(directions)} {'6um' if noise else '3um'}")
    return model, process(data, case), label


def _audits(d) -> tuple:
    return tuple(a for ex in d.weighing.explanations for a in getattr(ex.payload, "stop_audit", ()))


def _posteriors(d) -> dict:
    from femcheck.diagnose import evidence
    w = d.weighing
    return {m: {tuple(sorted(e.ids)): float(p) for e, p in
                zip(w.explanations, evidence.posterior(w.explanations, w.n_data, m))} for m in evidence.EVIDENCE_METHODS}


def compare(seed: int, *, sparse_only: bool = False, candidates=None) -> SetComparison:
    """Diagnose set ``seed`` with the early stops (as shipped) and without (every start to the end, audited)."""
    from femcheck.diagnose import diagnose
    from femcheck.diagnose.fitting import early_stop_rules

    model, readings, label = generated_set(seed, sparse_only=sparse_only)
    runs = {}
    for enabled in (True, False):
        with early_stop_rules(enabled):
            c0 = time.process_time()
            d = diagnose(model, readings, with_baseline=False, candidates=candidates)
            runs[enabled] = d, time.process_time() - c0
    (on, t_on), (off, t_off) = runs[True], runs[False]
    p_on, p_off = _posteriors(on), _posteriors(off)
    diff = max(abs(p_on[m].get(k, 0.0) - p_off[m].get(k, 0.0)) for m in p_on for k in set(p_on[m]) | set(p_off[m]))
    causes = lambda d: [(c.id, c.legs) for c in d.causes]
    return SetComparison(seed, label, _audits(on), _audits(off), float(diff), on.verdict == off.verdict,
                         causes(on) == causes(off), t_on, t_off)


def _stops(a, factor: float, rho_tol: float | None) -> str:
    """The rule ("start", "probe" or "") that stops audited start ``a`` at START_FACTOR ``factor`` with the gain-ratio
    check ``rho_tol`` (None: no check, the rule before it)."""
    trusted = lambda rho: rho_tol is None or not np.isfinite(rho_tol) or abs(rho - 1.0) <= rho_tol
    if a.floor_start > factor * a.stop_above and trusted(a.rho_start):
        return "start"
    if np.isfinite(a.floor_probe) and a.floor_probe > a.stop_above and trusted(a.rho_probe):
        return "probe"
    return ""


def violations(audits, factor: float, rho_tol: float | None) -> list:
    """The audited starts (fitted to the end) that the rules stop although their end-to-end chi^2 is within the
    threshold."""
    return [a for a in audits if _stops(a, factor, rho_tol) and a.chi2_end <= a.stop_above]


def evals_with_stops(audits, factor: float, rho_tol: float | None) -> int:
    """Residual evaluations the audited starts would cost with the rules (one start judgement costs ``nfev_start``,
    the probe ``nfev_probe``)."""
    cost = {"start": lambda a: a.nfev_start, "probe": lambda a: a.nfev_start + a.nfev_probe}
    return sum(cost.get(_stops(a, factor, rho_tol), lambda a: a.nfev_end)(a) for a in audits)


def summarize(sets) -> dict:
    from femcheck.diagnose.fitting import RHO_TOL, START_FACTOR
    from femcheck.experiment.foreign import FOREIGN
    on = [a for s in sets for a in s.audits_on]
    off = [a for s in sets for a in s.audits_off]
    within = [a for a in off if a.chi2_end <= a.stop_above]
    trusted = lambda rho: not np.isfinite(RHO_TOL) or abs(rho - 1.0) <= RHO_TOL
    crit = max((a.floor_start / a.stop_above for a in within if trusted(a.rho_start)), default=0.0)
    probe_crit = max((a.floor_probe / a.stop_above for a in within if np.isfinite(a.floor_probe)
                      and trusted(a.rho_probe)), default=0.0)
    cpu_on, cpu_off = sum(s.cpu_on_s for s in sets), sum(s.cpu_off_s for s in sets)
    n_off = max(sum(a.nfev_end for a in off), 1)
    out = {"sets": len(sets), "sets_full_protocol": sum("full" in s.label for s in sets),
           "sets_foreign": sum(any(f in s.label for f in FOREIGN) for s in sets),
           "start_factor": START_FACTOR, "rho_tol": RHO_TOL if np.isfinite(RHO_TOL) else "off",
           "pair_starts_audited": len(off),
           "pair_starts_ending_within_threshold": len(within),
           "pairs_stopped_at_start": sum(a.rule == "start" and a.applied for a in on),
           "pairs_stopped_after_probe": sum(a.rule == "probe" and a.applied for a in on),
           "violations": len(violations(off, START_FACTOR, RHO_TOL)),
           "max_abs_posterior_diff": max((s.posterior_diff for s in sets), default=0.0),
           "verdict_changes": sum(not s.verdict_same for s in sets),
           "causes_changes": sum(not s.causes_same for s in sets),
           "cpu_with_stops_s": round(cpu_on, 2), "cpu_without_stops_s": round(cpu_off, 2),
           "cpu_ratio_without_over_with": round(cpu_off / max(cpu_on, 1e-9), 3),
           "evals_saved_frac": round(1.0 - evals_with_stops(off, START_FACTOR, RHO_TOL) / n_off, 4),
           "floor_overshoot_max": max((a.floor_start / max(a.chi2_end, 1e-300) for a in off), default=0.0),
           "floor_overshoot_max_rho_trusted": max((a.floor_start / max(a.chi2_end, 1e-300) for a in off
                                                   if trusted(a.rho_start)), default=0.0),
           "start_factor_critical": crit,
           "start_factor_margin": START_FACTOR / crit if crit > 0 else float("inf"),
           "probe_floor_over_threshold_max_within": probe_crit}
    for f in FACTORS:
        tag = f"f{f:g}".replace(".", "p")
        out[f"violations_{tag}"] = len(violations(off, f, RHO_TOL))
        out[f"stopped_at_start_{tag}"] = sum(_stops(a, f, RHO_TOL) == "start" for a in off)
        out[f"evals_saved_frac_{tag}"] = round(1.0 - evals_with_stops(off, f, RHO_TOL) / n_off, 4)
    for rt in RHO_TOLS:         # the opt-in gain-ratio check at START_FACTOR
        tag = f"rho{rt:g}".replace(".", "p")
        out[f"violations_{tag}"] = len(violations(off, START_FACTOR, rt))
        out[f"evals_saved_frac_{tag}"] = round(1.0 - evals_with_stops(off, START_FACTOR, rt) / n_off, 4)
    return out


def run(n_sets: int = SETS, seed: int = 0) -> dict:
    sets = [compare(s) for s in range(seed, seed + n_sets)]
    return summarize(sets)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m femcheck.bench.early_stop", description=__doc__.split("\n")[0])
    ap.add_argument("--sets", type=int, default=SETS)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="reports/bench/early_stop.json")
    ap.add_argument("--dump", default="", help="also write every set's audits here (pickle, for re-analysis)")
    a = ap.parse_args(argv)
    from femcheck.bench.__main__ import machine
    from femcheck.report.atomic import write_text_atomic
    t0 = time.perf_counter()
    sets = []
    for s in range(a.seed, a.seed + a.sets):
        c = compare(s)
        sets.append(c)
        print(f"set {s} [{c.label}]: starts {len(c.audits_off)}, stopped start/probe "
              f"{sum(x.rule == 'start' and x.applied for x in c.audits_on)}/"
              f"{sum(x.rule == 'probe' and x.applied for x in c.audits_on)}, violations "
              f"{len(violations(c.audits_off, 1.5, None))}, |dp| {c.posterior_diff:.2e}, same verdict {c.verdict_same} "
              f"causes {c.causes_same}, cpu {c.cpu_on_s:.1f} / {c.cpu_off_s:.1f} s", flush=True)
    if a.dump:
        import pickle
        with open(a.dump, "wb") as fh:
            pickle.dump(sets, fh)
    fig = {"bench_wall_s": round(time.perf_counter() - t0, 3), **machine(), **summarize(sets),
           "command": f"python -m femcheck.bench.early_stop --sets {a.sets} --seed {a.seed}"}
    write_text_atomic(a.out, json.dumps(fig, indent=2) + "\n")
    print(json.dumps(fig, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
