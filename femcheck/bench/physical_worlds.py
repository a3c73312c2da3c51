"""Bench area ``physical_worlds``: the 6-PSU diagnosis on worlds that differ from the case *physically*.

Each world is a seeded random modified copy of the reference case (``cases/haptic_6psu.toml``), diagnosed against
the unmodified case. A change is one of

- ``proximal_link_modulus``: the proximal-link tubes' modulus x U(0.45, 0.6) (their compliance / that factor, an
  element scale of the chain: the tube's material is the guideways' too in the case file);
- ``guideway_section``: the guideway bar's width and depth x s, s ~ U(0.82, 0.88) (case parameters: bending and
  torsion compliance ~ s^-4); in one leg, that leg's guideway compliance x s^-4;
- ``pin_radius``: the U-joint pin radius x U(0.45, 0.55) (case parameter: pin bending ~ r^-4 and the line contact);
  in one leg, that leg's U-joint compliance x the all-legs ratio the chain gives for that radius;
- ``cable_modulus``: the cable modulus x U(0.55, 0.7) (case parameter); in one leg, that leg's actuation compliance
  x the all-legs ratio,

in one random leg or in all six; a world holds one change or two changes of different elements (1/2 each).

**The world is the detailed analytical chain of the modified case**, read by dial gauges
(:mod:`femcheck.experiment.dial_gauge`: 9 points, +-x +-y +-z, preload 5 N, total 20 N, 3 trials, 3 um scatter,
10 um steps), not the device FE: a device-FE world with contact joints needs its meshes and contact joint laws
measured again for every modified case (minutes of CPU per case on the 2-core machine, and the FE reading model
does not take element scales), so 30 FE worlds do not fit a bench run here. The chain world is built by the
element formulas of the case, not by the diagnosis's effect code; its limit is that the element laws are the ones
the diagnosis's element causes scale (a section change is not an exact scale of the guideway's 6x6 compliance, the
pin radius not of the U joint's).

Scoring, per world: the element of each named cause (``<element>_in_legs`` its element; ``actuation_compliance``
the actuation; the whole-device ids their elements: ``link_modulus`` guideway + proximal link,
``joint_contact_compliance`` both joints; ``leg_softening`` "whole leg"):

- ``right_element_first``: the first named cause is the changed element alone (for a pair: one of the two);
- ``both_named``: (pairs) both changed elements are named, each by a cause of its own element;
- ``wrong_whole_leg``: ``leg_softening`` is named;
- ``legs_right``: the named located cause of the first changed element holds exactly its legs.

Figures: the rates over the worlds (and over singles and pairs), the confusion matrix of the single changes
{changed element: {first named element: count}}, the pairs {changed elements: {named elements: count}}, each world's
row, CPU per world. ``python -m femcheck.bench physical_worlds`` (``WORLDS`` worlds,
seed 2026) or ``python -m femcheck.bench.physical_worlds --worlds N --seed S --jobs J``.
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np

AREA = "physical_worlds"
WORLDS = 30
SEED = 2026
CASE_PATH = "cases/haptic_6psu.toml"
DIRECTIONS = ("+x", "+y", "+z", "-x", "-y", "-z")
CHANGES = ("proximal_link_modulus", "guideway_section", "pin_radius", "cable_modulus")
#: the chain element each change moves
ELEMENT = {"proximal_link_modulus": "prox", "guideway_section": "lg", "pin_radius": "uj", "cable_modulus": "act"}
#: the elements a named cause moves
CAUSE_ELEMENTS = {"guideway_in_legs": ("lg",), "actuation_in_legs": ("act",), "spherical_joint_in_legs": ("sp",),
                  "proximal_link_in_legs": ("prox",), "universal_joint_in_legs": ("uj",),
                  "actuation_compliance": ("act",), "link_modulus": ("lg", "prox"),
                  "joint_contact_compliance": ("sp", "uj"), "leg_softening": ("whole leg",)}


def _all_legs_ratio(case, element: str, params: dict) -> float:
    """Compliance ratio of ``element`` (chain element key) between the case with ``params`` and the case: the
    factor a one-leg change of that parameter puts on that leg's element (from the chain's element compliances)."""
    from femcheck.chain import ELEMENTS
    from femcheck.chain.haptic_6psu_model import chain_element_compliances
    pose = np.concatenate([case.workspace.nominal_tcp_m, np.zeros(3)])[None]   # P0; element laws barely vary
    j = ELEMENTS.index(element)
    a = chain_element_compliances(case, pose)[0, 0, j]
    b = chain_element_compliances(case.with_params(**params), pose)[0, 0, j]
    return float(np.linalg.norm(b) / np.linalg.norm(a))   # Frobenius norm of the 6x6 compliance at C


def draw_change(rng, case, name: str, leg: int | None) -> tuple[dict, dict]:
    """(dial-gauge world entries, truth) of one change ``name`` in ``leg`` (None = all legs)."""
    el = ELEMENT[name]
    if name == "proximal_link_modulus":
        f = 1.0 / float(rng.uniform(0.45, 0.6))
        factor = np.ones(6) * f if leg is None else np.where(np.arange(6) == leg, f, 1.0)
        return {"element_scale": {el: factor}}, {"factor": f}
    if name == "guideway_section":
        s = float(rng.uniform(0.82, 0.88))
        params = {"guideway.width_radial_m": case.guideway.width_radial_m * s,
                  "guideway.depth_tangential_m": case.guideway.depth_tangential_m * s}
        truth = {"section_factor": s}
    elif name == "pin_radius":
        s = float(rng.uniform(0.45, 0.55))
        params = {"universal_joint.pin_radius_m": case.universal_joint.pin_radius_m * s}
        truth = {"radius_factor": s}
    else:
        s = float(rng.uniform(0.55, 0.7))
        params = {"actuation.cable_modulus_Pa": case.actuation.cable_modulus_Pa * s}
        truth = {"modulus_factor": s}
    if leg is None:
        return {"case_params": params}, truth
    f = _all_legs_ratio(case, el, params)
    return {"element_scale": {el: np.where(np.arange(6) == leg, f, 1.0)}}, {**truth, "factor": f}


def draw_world(seed: int, case) -> dict:
    """A random world: one or two changes of different elements, each in one leg or all (seeded)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 3))
    names = [CHANGES[i] for i in rng.choice(len(CHANGES), size=n, replace=False)]
    world, changes = {}, []
    for name in names:
        leg = None if rng.uniform() < 0.5 else int(rng.integers(6))
        part, truth = draw_change(rng, case, name, leg)
        for key, v in part.items():   # merge: two changes never touch the same element or parameter
            world.setdefault(key, {}).update(v)
        changes.append({"change": name, "element": ELEMENT[name], "legs": list(range(6)) if leg is None else [leg],
                        **truth})
    return {"seed": seed, "world": world, "changes": changes, "data_seed": int(rng.integers(1 << 30))}


def score(changes: list, causes: list) -> dict:
    """The world's row: what was named against what was changed (module docstring)."""
    named = [(c["id"], CAUSE_ELEMENTS.get(c["id"], ("other",)), c.get("legs", [])) for c in causes if c["id"] != "none"]
    truth = [c["element"] for c in changes]
    first = named[0][1] if named else ("none",)
    right_first = len(first) == 1 and first[0] in truth
    own = {el for _, els, _ in named if len(els) == 1 for el in els}
    first_change = changes[0]
    # actuation_compliance is the actuation changed alike in all six legs
    legs_right = any(len(els) == 1 and els[0] == first_change["element"]
                     and sorted(legs or (range(6) if n == "actuation_compliance" else [])) == first_change["legs"]
                     for n, els, legs in named)
    return {"named": [n for n, _, _ in named], "first_element": "+".join(first),
            "right_element_first": bool(right_first), "both_named": bool(set(truth) <= own),
            "wrong_whole_leg": any(n == "leg_softening" for n, _, _ in named), "legs_right": bool(legs_right)}


def run_world(seed: int) -> dict:
    import femcheck
    from femcheck.diagnose import AnalyticalChainModel, diagnose
    from femcheck.experiment.dial_gauge import dial_campaign
    from femcheck.measured import process
    case = femcheck.load_case(CASE_PATH)
    w = draw_world(seed, case)
    t0 = time.process_time()
    readings = process(dial_campaign(case, w["world"], seed=w["data_seed"], directions=DIRECTIONS).data, case)
    d = diagnose(AnalyticalChainModel(case, "detailed", "rigid"), readings, with_baseline=False).as_json()
    row = {"seed": seed, "changes": w["changes"], "verdict": d["verdict"],
           "causes": [{"id": c["id"], "legs": c.get("legs", []), "probability": c["probability"]} for c in d["causes"]],
           **score(w["changes"], d["causes"]), "cpu_s": round(time.process_time() - t0, 2)}
    return row


def summarize(rows: list) -> dict:
    singles = [r for r in rows if len(r["changes"]) == 1]
    pairs = [r for r in rows if len(r["changes"]) == 2]
    rate = lambda rs, k: round(float(np.mean([r[k] for r in rs])), 4) if rs else None
    confusion, named_pairs = {}, {}
    for r in singles:
        row = confusion.setdefault(r["changes"][0]["element"], {})
        row[r["first_element"]] = row.get(r["first_element"], 0) + 1
    for r in pairs:   # changed elements -> the elements named (each cause's, in order)
        key = "+".join(sorted(c["element"] for c in r["changes"]))
        got = "+".join("+".join(CAUSE_ELEMENTS.get(n, ("other",))) for n in r["named"]) or "none"
        row = named_pairs.setdefault(key, {})
        row[got] = row.get(got, 0) + 1
    return {"worlds": len(rows), "singles": len(singles), "pairs": len(pairs),
            "right_element_first_rate": rate(rows, "right_element_first"),
            "right_element_first_rate_singles": rate(singles, "right_element_first"),
            "right_element_first_rate_pairs": rate(pairs, "right_element_first"),
            "both_named_rate_pairs": rate(pairs, "both_named"),
            "wrong_whole_leg_rate": rate(rows, "wrong_whole_leg"),
            "legs_right_rate": rate(rows, "legs_right"),
            "explained_rate": rate([{"x": r["verdict"] == "explained"} for r in rows], "x"),
            "cpu_per_world_s_median": round(float(np.median([r["cpu_s"] for r in rows])), 2) if rows else None,
            "world": "detailed analytical chain of the modified case (not the device FE; module docstring)",
            "confusion_singles_changed_vs_first_named": confusion, "pairs_changed_vs_named": named_pairs,
            "rows": rows}


def run(n_worlds: int = WORLDS, seed: int = SEED, jobs: int = 1) -> dict:
    from concurrent.futures import ProcessPoolExecutor
    seeds = range(seed, seed + n_worlds)
    if jobs <= 1:
        return summarize([run_world(s) for s in seeds])
    with ProcessPoolExecutor(jobs) as ex:   # one world per process: each diagnosis is single-threaded
        return summarize(list(ex.map(run_world, seeds)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m femcheck.bench.physical_worlds", description=__doc__.split("\n")[0])
    ap.add_argument("--worlds", type=int, default=WORLDS)
    ap.add_argument("--seed", type=int, default=SEED)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", default="reports/bench/physical_worlds.json")
    a = ap.parse_args(argv)
    from femcheck.bench.__main__ import machine
    from femcheck.report.atomic import write_text_atomic
    t0 = time.perf_counter()
    fig = run(a.worlds, a.seed, a.jobs)
    fig = {"bench_wall_s": round(time.perf_counter() - t0, 3), **machine(), **fig,
           "command": f"python -m femcheck.bench.physical_worlds --worlds {a.worlds} --seed {a.seed} --jobs {a.jobs}"}
    write_text_atomic(a.out, json.dumps(fig, indent=2) + "\n")
    print(json.dumps({k: v for k, v in fig.items() if k != "rows"}, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
