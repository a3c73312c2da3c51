"""Are the serial diagnosis's probabilities calibrated? A reliability table on generated robots.

Worlds. Each set alternates the two generated robots of :mod:`femcheck.robot.simulate` (a torso with two 7-joint
arms, sigma 0.2 mm; a 6-joint industrial arm with nominal drive springs, sigma 0.05 mm), each with its own seed,
random geometric errors (1 mm, 0.2 deg), a random sensor frame and Gaussian noise. The hidden explanation is drawn
from the diagnosis's own size prior (:func:`femcheck.diagnose.evidence.size_prior`: none, a single cause, a pair
with 1/3 each, uniform within the size over the causes the robot admits). The serial diagnosis weighs its rivals by
BIC, which has no explicit parameter prior; the hidden magnitude is therefore drawn from a stated generating
prior: the RMS marker motion the cause makes, log-uniform between ``RMS_SIGMA`` (0.5 to 8 sigma), placed on one
to three random joints (torsion), one loaded joint (gear clearance) or all joints (tilt, bending, mass scale).
Few poses (``POSES``) keep the probabilities away from 0 and 1.

Each set is diagnosed (every single cause and every pair weighed, 5-fold cross-validation); each explanation's
posterior probability is paired with whether it is the hidden one, and each cause's marginal probability with
whether it is hidden. The reliability tables, the expected calibration error (ECE), the Brier score and the null
distribution of the ECE of a perfectly calibrated predictor with the same predictions are those of the 6-PSU
calibration bench (:func:`femcheck.bench.calibration.reliability`, :func:`femcheck.bench.calibration.ece_null`).

``python -m femcheck.bench.serial_calibration [--sets 40] [--jobs 1] [--seed 0]
[--out reports/diagnose/serial_calibration.md]`` (also writes the JSON next to it).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import time

import numpy as np

POSES = 40
RMS_SIGMA = (0.5, 8.0)
ROBOTS = ("humanoid17", "industrial6")


@dataclasses.dataclass(frozen=True)
class SerialSet:
    """One diagnosed world: ``hidden`` cause ids (sorted; empty = none), ``explanations`` [(sorted ids,
    probability)], ``causes`` the ids weighed, ``verdict``, ``seconds`` (CPU)."""

    seed: int
    robot: str
    hidden: tuple[str, ...]
    rms_sigma: tuple[float, ...]
    explanations: tuple
    causes: tuple[str, ...]
    verdict: str
    seconds: float


def _robot(seed: int):
    from femcheck.robot.simulate import humanoid_case, industrial_case
    robot = ROBOTS[seed % 2]
    if robot == "humanoid17":
        return robot, humanoid_case(seed, head=False, sigma_m=2e-4)[0], 2e-4
    return robot, industrial_case(seed, sigma_m=5e-5, springs=True)[0], 5e-5


def _placement(cid: str, tree, rng) -> dict:
    """Where the hidden cause sits: {row name or 'all': 1.0} (a direction; :func:`scaled` sets the size)."""
    if cid == "joint_torsion_compliance":
        k = int(rng.integers(1, 4))
        return {tree.names[r]: 1.0 for r in rng.choice(tree.independent, size=k, replace=False)}
    if cid == "gear_clearance":
        loaded = [r for r in tree.independent if tree.names[r][-1] in "234"]     # shoulder/elbow-like joints
        return {tree.names[int(rng.choice(loaded))]: 1.0}
    return {"all": 1.0}


def one_set(seed: int) -> SerialSet:
    """Generate, simulate and diagnose world ``seed`` (module docstring)."""
    from femcheck.robot.diagnosis import diagnose_tree
    from femcheck.robot.simulate import scaled, simulate_positions
    rng = np.random.default_rng(20_000 + seed)
    robot, case, sigma = _robot(seed)
    tree = case.tree
    pool = ["joint_torsion_compliance", "joint_tilt_compliance", "gear_clearance", "link_bending_compliance"]
    if robot == "industrial6":
        pool.append("mass_scale")
    size = int(rng.integers(0, 3))
    hidden = tuple(sorted(rng.choice(pool, size=size, replace=False))) if size else ()
    effects, rms = {}, []
    for cid in hidden:
        r = float(np.exp(rng.uniform(*np.log(RMS_SIGMA))))
        rms.append(r)
        effects.update(scaled(case, {cid: _placement(cid, tree, rng)}, r * sigma))
    data, _ = simulate_positions(case, POSES, effects=effects, sigma_m=sigma, seed=seed)
    c0 = time.process_time()
    d = diagnose_tree(case, data)
    w = d.weighing
    expl = tuple((tuple(sorted(e.ids)), float(p)) for e, p in zip(w.explanations, w.probability))
    causes = tuple(sorted({c for ids, _ in expl for c in ids}))
    return SerialSet(seed, robot, hidden, tuple(rms), expl, causes, d.verdict, time.process_time() - c0)


def serial_calibration(n_sets: int = 40, jobs: int = 1, seed: int = 0) -> dict:
    """Diagnose ``n_sets`` worlds (seeds ``seed`` ..); the explanation-, cause- and leader-level reliability tables
    over all sets and per robot, each with the ECE null of a calibrated predictor (95 % quantile, p-value)."""
    from femcheck.bench.calibration import _tables, ece_null
    seeds = list(range(seed, seed + n_sets))
    if jobs > 1:
        from concurrent.futures import ProcessPoolExecutor
        with ProcessPoolExecutor(jobs) as ex:
            sets = list(ex.map(one_set, seeds))
    else:
        sets = [one_set(s) for s in seeds]
    out: dict = {"n_sets": n_sets, "poses": POSES, "rms_sigma_range": list(RMS_SIGMA)}
    for tag, sub in (("all", sets), *((r, [s for s in sets if s.robot == r]) for r in ROBOTS)):
        tabs = _tables(sub, lambda s: s.explanations)
        for level in ("explanations", "causes", "leader"):
            t = tabs[level]
            preds = [p for s in sub for ids, p in s.explanations] if level == "explanations" else \
                [sum(p for ids, p in s.explanations if c in ids) for s in sub for c in s.causes] \
                if level == "causes" else [max(p for _, p in s.explanations) for s in sub]
            null = ece_null(preds) if preds else np.array([np.nan])
            out[f"{tag}.{level}_ece"] = t["ece"]
            out[f"{tag}.{level}_brier"] = t["brier"]
            out[f"{tag}.{level}_n"] = t["n"]
            out[f"{tag}.{level}_ece_null95"] = float(np.quantile(null, 0.95))
            out[f"{tag}.{level}_ece_p_value"] = float(np.mean(null >= t["ece"]))
            out[f"{tag}.{level}_table"] = t
        out[f"{tag}.n_sets"] = len(sub)
    out["leader_right_rate"] = float(np.mean([max(s.explanations, key=lambda t: t[1])[0] == s.hidden for s in sets]))
    out["mean_diagnosis_cpu_s"] = float(np.mean([s.seconds for s in sets]))
    out["sets"] = [dataclasses.asdict(s) for s in sets]
    return out


def markdown(res: dict, command: str) -> str:
    lines = [f"# Serial diagnosis: calibration of the probabilities ({res['n_sets']} worlds, {res['poses']} poses each)",
             "", f"`{command}`", "",
             "| robots | level | predictions | ECE | ECE null 95 % (calibrated predictor) | p-value | Brier |",
             "|---|---|---|---|---|---|---|"]
    for tag in ("all", *ROBOTS):
        for level in ("explanations", "causes", "leader"):
            lines.append(f"| {tag} ({res[f'{tag}.n_sets']} sets) | {level} | {res[f'{tag}.{level}_n']} | "
                         f"{res[f'{tag}.{level}_ece']:.3f} | {res[f'{tag}.{level}_ece_null95']:.3f} | "
                         f"{res[f'{tag}.{level}_ece_p_value']:.2f} | {res[f'{tag}.{level}_brier']:.3f} |")
    lines += ["", f"Leader right in {res['leader_right_rate']:.0%} of the sets; mean diagnosis "
              f"{res['mean_diagnosis_cpu_s']:.2f} s CPU.", "", "Cause-level reliability (all sets):", "",
              "| predicted | n | mean predicted | observed | se |", "|---|---|---|---|---|"]
    for b in res["all.causes_table"]["bins"]:
        if b["n"]:
            lines.append(f"| {b['lo']:.1f}-{b['hi']:.1f} | {b['n']} | {b['mean_predicted']:.3f} | {b['observed']:.3f} | "
                         f"{b['observed_se']:.3f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    from pathlib import Path

    from femcheck.report.atomic import write_text_atomic
    ap = argparse.ArgumentParser(prog="python -m femcheck.bench.serial_calibration", description=__doc__.split("\n")[0])
    ap.add_argument("--sets", type=int, default=40)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="reports/diagnose/serial_calibration.md")
    a = ap.parse_args(argv)
    if a.sets < 2 or a.jobs < 1:
        ap.error("--sets: expected >= 2; --jobs: expected >= 1")
    res = serial_calibration(a.sets, a.jobs, a.seed)
    command = "python -m femcheck.bench.serial_calibration " + " ".join(argv if argv is not None else [])
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out, markdown(res, command.strip()))
    write_text_atomic(out.with_suffix(".json"), json.dumps(res, indent=1, default=float) + "\n")
    print(markdown(res, command.strip()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
