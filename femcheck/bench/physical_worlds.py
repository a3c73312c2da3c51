"""Bench area ``physical_worlds``: the 6-PSU diagnosis on worlds that differ from the case *physically*.

Each world is a seeded random modified copy of the reference case (``cases/haptic_6psu.toml``), **simulated by the
device FE** and diagnosed against the unmodified case. A change is one of (:func:`changed_case`, the one place that
says which case values a change sets):

- ``proximal_link_modulus``: the proximal-link tubes made of another real material, drawn from
  :data:`TUBE_MATERIALS` (magnesium alloy AZ31B, or glass-fibre polyamide PA66-GF30; a material of their own, the
  guideways and yokes keep the aluminium);
- ``guideway_section``: the guideway bar's width and depth x U(0.82, 0.88) (bending and torsion ~ s^-4);
- ``pin_radius``: the U-joint pins replaced by the next smaller standard dowel pins: a seeded draw among the
  :data:`PIN_SIZES_BELOW` nominal diameters of :data:`PIN_DIAMETERS_M` (ISO 8734 / ISO 2338 series) below the
  case's pin diameter (the reference's Ø2 mm pin: Ø1.5 mm, x 0.75, or Ø1 mm, x 0.5). A thinner pin bends into its
  bore away from the loaded lines; the U joint's contact FE widens its candidate band until the contact stays inside
  it (:func:`femcheck.fe_device.joint_models.solve_widening`); each size is measured once (minutes of CPU) and
  cached on disk by its inputs;
- ``cable_modulus``: the cable modulus x U(0.55, 0.7),

in one random leg or in all six; a world holds one change or two changes of different elements (1/2 each).

**The world** (:class:`femcheck.experiment.device_fe_world.DeviceFEWorld`): the detailed device FE of ``verify``
(solid guideway and link super-elements, actuation FE, frictional contact joints with contact-FE-measured laws),
each leg built from its own changed case; read by dial gauges (:mod:`femcheck.experiment.dial_gauge`: 9 points,
+-x +-y +-z, preload 5 N, total 20 N, 3 trials, 3 um scatter, 10 um steps). Solid parts and joints on the
``coarse`` mesh (``--mesh``); the U joint of a changed pin is measured by its contact FE (cached on disk by its
inputs), an unchanged joint is the reference's law.

**The model diagnosed** (:class:`femcheck.diagnose.fe_model.FEAnchoredChainModel`): the unmodified case's
detailed chain plus its idealization gap to the device FE of the *unmodified* case on the same mesh (what a user
can compute from the case alone): the unchanged world is explained with no cause, and the causes' effects are the
chain's. The chain's joints are those nearer to that FE (:meth:`~.FEAnchoredChainModel.nearest`: released, as the
frictional joints slip at the test loads). Its U joint is the device FE's own: the contact-FE law of the case's pin
and of pins of :data:`~femcheck.diagnose.pin_law.RADIUS_FACTORS` x its radius (:mod:`femcheck.diagnose.pin_law`,
computed from the case alone), interpolated in the pin's bending compliance (r^-4), which is the U-joint factor a
cause fits: a thin pin's stiffening is then the U joint's, not the ball's. The world's pins (0.75 and 0.5 x) lie
between those nodes, so the diagnosis fits an interpolated law, never the one its world used.

Scoring, per world: the element of each named cause (``<element>_in_legs`` its element; ``actuation_compliance``
the actuation; the whole-device ids their elements: ``link_modulus`` guideway + proximal link,
``joint_contact_compliance`` both joints; ``leg_softening`` "whole leg"). Where the readings cannot separate a named
cause from other element types on its legs, the diagnosis itself reports them as one alias group
(:func:`femcheck.diagnose.selection.alias_groups`; e.g. the proximal tube and the U joint of one leg, two springs in
series on the link's line when the joints slip). Each rate is given two ways:

- ``right_element_first_strict``: the first named cause is the changed element alone (for a pair: one of the two);
  ``right_element_first``: the same, or the first named cause heads an alias group the diagnosis declares
  inseparable and one member of that group is the changed element alone;
- ``both_named_strict``: (pairs) both changed elements are named, each by a cause of its own element;
  ``both_named``: each by a named cause of its own element or by a member of a named cause's alias group;
- ``wrong_whole_leg``: ``leg_softening`` is named;
- ``legs_right``: the named located cause of the first changed element holds exactly its legs.

**Detectability and what is scored.** A change whose effect on the readings is below their scatter cannot be named
by any method. Each changed element's signal-to-noise ratio is the RMS over the total readings of the change it alone
makes to the noise-free device-FE deflection (total - preload; the world with only that change against the unchanged
FE world, :func:`femcheck.experiment.dial_gauge.device_change_rms`) over the reading scatter ``SCATTER_M``; a world is
*detectable* when every changed element has SNR >= :data:`DETECTABLE_SNR`. A run draws seeded random worlds (seeds S,
S + 1, ...) until it holds ``--worlds`` detectable ones (:func:`draw_until`; at most :data:`MAX_DRAWS_FACTOR` x as
many draws) and keeps every draw. The headline rates (``right_element_first_rate``, ``both_changes_named_rate``,
``wrong_whole_leg_rate`` and the ``_strict`` ones) are over the **detectable worlds**; the same rates over every
scored draw sit beside them as ``*_all_draws``. An undetectable draw asks no name of the diagnosis, only that it
does not name a wrong one: ``honesty_rate_undetectable`` is the share of undetectable draws where no named cause is
of an unchanged element (named none, or each named cause is a changed element alone or declares one in its alias
group). A draw whose own FE fails has no readings: kept, listed in ``worlds_failed_seeds``, not scored.

Figures (flat keys, :data:`DEFINITIONS` written into them): the rates and counts over the detectable worlds and over
all draws, the honesty of the undetectable draws, the confusion of the single changes (changed element -> first
named alias group) and of the pairs as text (detectable; ``*_all_draws``), each undetectable draw and what was named,
CPU per world; each world's row goes to ``reports/bench/detail/physical_worlds_worlds.json``. ``python -m
femcheck.bench physical_worlds`` (until ``WORLDS`` detectable worlds, seed 2026) or ``python -m
femcheck.bench.physical_worlds --worlds N --seed S --jobs J``.
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np

from femcheck.diagnose.pin_law import RADIUS_FACTORS

AREA = "physical_worlds"
#: detectable worlds a run draws until (every draw kept), and the most draws it makes per detectable world asked
WORLDS = 30
MAX_DRAWS_FACTOR = 4
SEED = 2026
CASE_PATH = "cases/haptic_6psu.toml"
DETAIL_PATH = "reports/bench/detail/physical_worlds_worlds.json"
DIRECTIONS = ("+x", "+y", "+z", "-x", "-y", "-z")
CHANGES = ("proximal_link_modulus", "guideway_section", "pin_radius", "cable_modulus")
#: the chain element each change moves
ELEMENT = {"proximal_link_modulus": "prox", "guideway_section": "lg", "pin_radius": "uj", "cable_modulus": "act"}
#: nominal diameters (m) of standard dowel pins (ISO 8734 hardened, ISO 2338 unhardened; the sizes both series
#: share up to 6 mm) and how many of the next smaller ones a ``pin_radius`` world draws from
PIN_DIAMETERS_M = (1.0e-3, 1.5e-3, 2.0e-3, 2.5e-3, 3.0e-3, 4.0e-3, 5.0e-3, 6.0e-3)
PIN_SIZES_BELOW = 2
#: the tube materials a ``proximal_link_modulus`` world draws from: {name: (E Pa, nu, density kg/m^3)}; room
#: temperature handbook values: magnesium alloy AZ31B-H24 (ASM Handbook vol. 2), glass-fibre polyamide PA66-GF30
#: dry as moulded (typical injection-moulding grade datasheets: tensile modulus ~10 GPa)
TUBE_MATERIALS = {"magnesium_AZ31B": (45.0e9, 0.35, 1770.0), "PA66_GF30": (10.0e9, 0.35, 1360.0)}
#: the dial campaign's reading scatter (m) and the SNR a changed element needs to count as detectable
SCATTER_M = 3e-6
DETECTABLE_SNR = 3.0
#: the elements a named cause moves
CAUSE_ELEMENTS = {"guideway_in_legs": ("lg",), "actuation_in_legs": ("act",), "spherical_joint_in_legs": ("sp",),
                  "proximal_link_in_legs": ("prox",), "universal_joint_in_legs": ("uj",),
                  "actuation_compliance": ("act",), "link_modulus": ("lg", "prox"),
                  "joint_contact_compliance": ("sp", "uj"), "leg_softening": ("whole leg",)}


def changed_case(case, change: str, factor: float, material: str | None = None) -> dict:
    """{dotted case key: value} that writes ``change`` with ``factor`` into ``case`` (the only place that knows
    how a physical change is spelled in the case file). A tube ``material`` (key of :data:`TUBE_MATERIALS`) sets
    the tubes' modulus, Poisson ratio and density; without it the tubes' modulus is ``factor`` x the case's."""
    if change == "proximal_link_modulus":   # a tube material of its own: the guideways and yokes keep the aluminium
        m = case.proximal_link.material
        E, nu, rho = TUBE_MATERIALS[material] if material else (m.E_Pa * factor, m.nu, m.density_kg_m3)
        return {"materials.tube_alloy.E_Pa": E, "materials.tube_alloy.nu": nu,
                "materials.tube_alloy.density_kg_m3": rho, "proximal_link.material": "tube_alloy"}
    if change == "guideway_section":
        return {"guideway.width_radial_m": case.guideway.width_radial_m * factor,
                "guideway.depth_tangential_m": case.guideway.depth_tangential_m * factor}
    if change == "pin_radius":
        return {"universal_joint.pin_radius_m": case.universal_joint.pin_radius_m * factor}
    if change == "cable_modulus":
        return {"actuation.cable_modulus_Pa": case.actuation.cable_modulus_Pa * factor}
    raise ValueError(f"unknown change {change!r}; expected one of {', '.join(CHANGES)}")


def pin_factors(case) -> tuple:
    """The radius factors of the :data:`PIN_SIZES_BELOW` standard pin diameters next below the case's pin."""
    d = 2.0 * case.universal_joint.pin_radius_m
    below = [x for x in PIN_DIAMETERS_M if x < d * (1.0 - 1e-9)][-PIN_SIZES_BELOW:]
    if not below:
        raise ValueError(f"pin diameter {d * 1e3:g} mm: no standard dowel pin below it in PIN_DIAMETERS_M")
    return tuple(x / d for x in reversed(below))


def draw_factor(rng, case, change: str) -> tuple[float, str | None]:
    """The seeded magnitude of ``change`` (module doc): (factor, tube material name or None); for a tube material
    the factor is its modulus over the case's tube modulus."""
    if change == "pin_radius":
        sizes = pin_factors(case)
        return float(sizes[int(rng.integers(len(sizes)))]), None
    if change == "proximal_link_modulus":
        name = sorted(TUBE_MATERIALS)[int(rng.integers(len(TUBE_MATERIALS)))]
        return TUBE_MATERIALS[name][0] / case.proximal_link.material.E_Pa, name
    lo, hi = {"guideway_section": (0.82, 0.88), "cable_modulus": (0.55, 0.7)}[change]
    return float(rng.uniform(lo, hi)), None


def draw_world(seed: int, case=None) -> dict:
    """A random world: one or two changes of different elements, each in one leg or all (seeded; ``case`` the
    reference, default :data:`CASE_PATH`)."""
    if case is None:
        import femcheck
        case = femcheck.load_case(CASE_PATH)
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 3))
    names = [CHANGES[i] for i in rng.choice(len(CHANGES), size=n, replace=False)]
    changes = []
    for name in names:
        leg = None if rng.uniform() < 0.5 else int(rng.integers(6))
        factor, material = draw_factor(rng, case, name)
        changes.append({"change": name, "element": ELEMENT[name], "factor": factor,
                        "legs": list(range(6)) if leg is None else [leg], **({"material": material} if material else {})})
    return {"seed": seed, "changes": changes, "data_seed": int(rng.integers(1 << 30))}


def leg_cases(case, changes: list) -> tuple:
    """(6,) the case of each leg: the reference with the changes that reach that leg (legs alike share one)."""
    per_leg = [{} for _ in range(6)]
    for c in changes:
        for leg in c["legs"]:
            per_leg[leg].update(changed_case(case, c["change"], c["factor"], c.get("material")))
    built: dict = {}
    for p in per_leg:
        key = repr(sorted(p.items()))
        if key not in built:
            built[key] = case.with_params(**p) if p else case
    return tuple(built[repr(sorted(p.items()))] for p in per_leg)


def _group_of(cause: dict, groups: list) -> list:
    """The element tuples of the members of ``cause``'s alias group (empty when the diagnosis declares none)."""
    for g in groups:
        if g["cause"] == cause["id"] and list(g["legs"]) == list(cause.get("legs", [])):
            return [CAUSE_ELEMENTS.get(m["id"], ("other",)) for m in g["members"]]
    return []


def score(changes: list, causes: list, alias_groups: list = ()) -> dict:
    """The world's row: what was named against what was changed, strictly and with the diagnosis's own alias
    groups (module docstring)."""
    real = [c for c in causes if c["id"] != "none"]
    named = [(c["id"], CAUSE_ELEMENTS.get(c["id"], ("other",)), c.get("legs", [])) for c in real]
    truth = [c["element"] for c in changes]
    first = named[0][1] if named else ("none",)
    right_first = len(first) == 1 and first[0] in truth
    first_group = _group_of(real[0], alias_groups) if real else []
    right_first_alias = right_first or any(len(els) == 1 and els[0] in truth for els in first_group)
    own = {el for _, els, _ in named if len(els) == 1 for el in els}
    own_alias = own | {els[0] for c in real for els in _group_of(c, alias_groups) if len(els) == 1}
    first_change = changes[0]
    # actuation_compliance is the actuation changed alike in all six legs
    legs_right = any(len(els) == 1 and els[0] == first_change["element"]
                     and sorted(legs or (range(6) if n == "actuation_compliance" else [])) == first_change["legs"]
                     for n, els, legs in named)
    # honest: no named cause claims an unchanged element (each is a changed element alone, or the diagnosis declares
    # it inseparable from a changed element alone); naming nothing is honest
    claims_right = [(len(els) == 1 and els[0] in truth)
                    or any(len(g) == 1 and g[0] in truth for g in _group_of(c, alias_groups))
                    for c, (_, els, _) in zip(real, named)]
    return {"named": [n for n, _, _ in named], "first_element": "+".join(first),
            "first_group": "\u2261".join("+".join(els) for els in first_group) or "+".join(first),
            "right_element_first_strict": bool(right_first), "right_element_first": bool(right_first_alias),
            "both_named_strict": bool(set(truth) <= own), "both_named": bool(set(truth) <= own_alias),
            "wrong_whole_leg": any(n == "leg_softening" for n, _, _ in named), "legs_right": bool(legs_right),
            "honest": bool(all(claims_right))}


_ANCHORS: dict = {}


def run_world(seed: int, mesh: str = "coarse", world: dict | None = None) -> dict:
    """One world's row (module doc): the world of ``seed`` (:func:`draw_world`), or ``world`` as given
    ({"changes": [...], "data_seed": int}, e.g. a fixed world of a test)."""
    import femcheck
    from femcheck.diagnose import diagnose
    from femcheck.diagnose.fe_model import FEAnchoredChainModel
    from femcheck.diagnose.pin_law import pin_law_table
    from femcheck.experiment.device_fe_world import DeviceFEWorld
    from femcheck.experiment.dial_gauge import dial_campaign
    from femcheck.errors import ConvergenceError
    from femcheck.measured import process
    case = femcheck.load_case(CASE_PATH)
    w = world or draw_world(seed, case)
    t0 = time.process_time()
    world = DeviceFEWorld(case, leg_cases(case, w["changes"]), mesh=mesh)
    try:
        readings = process(dial_campaign(case, {"device": world}, seed=w["data_seed"], directions=DIRECTIONS,
                                         scatter_m=SCATTER_M).data, case)
    except ConvergenceError as exc:   # the world's own FE has no answer: no readings, the world is not scored
        return {"seed": seed, "changes": w["changes"], "world_failed": str(exc).split(";")[0],
                "cpu_s": round(time.process_time() - t0, 2)}
    t1 = time.process_time()
    try:
        snr = signal_to_noise(case, w["changes"], world, mesh)
    except ConvergenceError as exc:   # a one-change world's FE has no answer: detectability unknown, not scored
        return {"seed": seed, "changes": w["changes"], "world_failed": "one-change world: " + str(exc).split(";")[0],
                "cpu_s": round(time.process_time() - t0, 2)}
    t2 = time.process_time()
    if mesh not in _ANCHORS:   # the unmodified case's: one per process, its gap table is shared by the worlds
        tot = readings.total_state
        device = DeviceFEWorld.of(case, mesh=mesh)
        _ANCHORS[mesh] = FEAnchoredChainModel.nearest(case, device, readings.pose[tot], readings.force[tot],
                                                      pin_laws=pin_law_table(case, device.joint_mesh))
    model = _ANCHORS[mesh]
    d = diagnose(model, readings, with_baseline=False).as_json()
    changes = [{**c, "snr": round(float(s), 2)} for c, s in zip(w["changes"], snr["each"])]
    row = {"seed": seed, "changes": changes, "verdict": d["verdict"], "chain_joints": model.joints,
           "causes": [{"id": c["id"], "legs": c.get("legs", []), "probability": c["probability"],
                       "params": c.get("params")} for c in d["causes"]],
           "alias_groups": [{"cause": g["cause"], "legs": g["legs"], "members": [m["label"] for m in g["members"]],
                             "probability": g["probability"]} for g in d["alias_groups"]],
           **score(w["changes"], d["causes"], d["alias_groups"]), "snr_world": round(float(snr["world"]), 2),
           "detectable": bool(min(snr["each"]) >= DETECTABLE_SNR), "world_cpu_s": round(t1 - t0, 2),
           "snr_cpu_s": round(t2 - t1, 2), "cpu_s": round(time.process_time() - t0, 2)}
    return row


_REFERENCE: dict = {}


def signal_to_noise(case, changes: list, world, mesh: str) -> dict:
    """{"each": (n,) SNR of each change alone, "world": SNR of the world}: the RMS over the campaign's total readings
    of the noise-free change of the device-FE deflection against the unchanged FE world, over ``SCATTER_M`` (module
    docstring, detectability). A single change's world is ``world`` itself."""
    from femcheck.experiment.device_fe_world import DeviceFEWorld
    from femcheck.experiment.dial_gauge import device_change_rms
    if mesh not in _REFERENCE:
        _REFERENCE[mesh] = DeviceFEWorld.of(case, mesh=mesh)
    alone = [world] if len(changes) == 1 else [DeviceFEWorld(case, leg_cases(case, [c]), mesh=mesh) for c in changes]
    worlds = alone if len(changes) == 1 else alone + [world]
    rms = device_change_rms(case, worlds, _REFERENCE[mesh], directions=DIRECTIONS) / SCATTER_M
    return {"each": rms[:len(changes)], "world": rms[-1]}


def _short(changes: list) -> str:
    return " + ".join(f"{c['element']}[{'all' if len(c['legs']) == 6 else c['legs'][0]}]" for c in changes)


def confusion_table(rows: list, column: str = "first_element") -> str:
    """The single changes as a text table: changed element (row) x first named element (column; ``first_group``:
    the first named cause's alias group, members joined by the identity sign), counts."""
    singles = [r for r in rows if len(r["changes"]) == 1]
    changed = sorted({r["changes"][0]["element"] for r in singles})
    named = sorted({r[column] for r in singles})
    head = ["changed \\ first named"] + named
    body = [[c] + [str(sum(1 for r in singles if r["changes"][0]["element"] == c and r[column] == n))
                   for n in named] for c in changed]
    width = [max(len(x[k]) for x in [head] + body) for k in range(len(head))]
    return "\n".join(" | ".join(x[k].ljust(width[k]) for k in range(len(head))) for x in [head] + body)


#: the definitions of the flat figures, written into the figures
DEFINITIONS = {
    "detectable": f"every changed element alone moves the noise-free device-FE readings (total - preload) by an RMS "
                  f">= {DETECTABLE_SNR:g} x the reading scatter {SCATTER_M * 1e6:g} um; a change below that is within "
                  f"the scatter of each reading and no method can be asked to name it",
    "draws": "seeded random worlds are drawn (seeds S, S+1, ...) until the detectable ones reach the number asked "
             "for; every draw is kept and reported",
    "right_element_first_rate": "over the detectable worlds: the first named cause is a changed element alone, or "
                                "heads an alias group that the diagnosis declares inseparable (readings within chi2 "
                                "9) with a changed element alone among its members",
    "right_element_first_rate_strict": "over the detectable worlds: the first named cause is a changed element alone",
    "both_changes_named_rate": "over the detectable two-change worlds: each changed element is named by a cause of "
                               "its own element or by a member of a named cause's alias group",
    "both_changes_named_rate_strict": "over the detectable two-change worlds: each changed element is named by a "
                                      "cause of its own element",
    "wrong_whole_leg_rate": "over the detectable worlds: leg_softening (a uniform whole-leg factor) is named",
    "_all_draws": "the same rate over every scored draw, detectable or not (a world whose own FE failed has no "
                  "readings and is not scored)",
    "honesty_rate_undetectable": "over the undetectable draws: the diagnosis names no cause of an unchanged element "
                                 "(it names none, or every named cause is a changed element alone or declares a "
                                 "changed element alone in its alias group)",
}


def _rates(rows: list, suffix: str) -> dict:
    pairs = [r for r in rows if len(r["changes"]) == 2]
    out = {}
    for key, src, rs in (("right_element_first", "right_element_first", rows),
                         ("right_element_first", "right_element_first_strict", rows),
                         ("both_changes_named", "both_named", pairs), ("both_changes_named", "both_named_strict", pairs),
                         ("wrong_whole_leg", "wrong_whole_leg", rows)):
        tail = "_strict" if src.endswith("_strict") else ""
        out[f"{key}_rate{tail}{suffix}"] = _rate(rs, src)
        out[f"{key}_count{tail}{suffix}"] = int(sum(r[src] for r in rs))
    out[f"pairs{suffix}"] = len(pairs)   # the worlds: worlds_detectable, worlds_drawn - worlds_failed
    if suffix:   # the descriptive figures below: the headline (detectable) set only
        return out
    out["singles"] = len(rows) - len(pairs)
    out["legs_right_rate"] = _rate(rows, "legs_right")
    out["explained_rate"] = _rate([{"x": r["verdict"] == "explained"} for r in rows], "x")
    out["first_alias_group_size_mean"] = (
        round(float(np.mean([r["first_group"].count("\u2261") + 1 for r in rows])), 3) if rows else None)
    return out


def _rate(rows: list, key: str):
    return round(float(np.mean([r[key] for r in rows])), 4) if rows else None


def _confusions(rows: list, suffix: str) -> dict:
    """The single changes (changed element > first named group) and the pairs (changed elements > the elements
    named, each cause's, in order) as counted text."""
    confusion, named_pairs = {}, {}
    for r in rows:
        if len(r["changes"]) == 1:
            key = f"{r['changes'][0]['element']}>{r['first_group']}"
            confusion[key] = confusion.get(key, 0) + 1
        else:
            got = "+".join("+".join(CAUSE_ELEMENTS.get(n, ("other",))) for n in r["named"]) or "none"
            key = f"{'+'.join(sorted(c['element'] for c in r['changes']))}>{got}"
            named_pairs[key] = named_pairs.get(key, 0) + 1
    return {f"confusion_singles_changed_to_first_named{suffix}":
            ", ".join(f"{k} {v}" for k, v in sorted(confusion.items())) or "none",
            f"pairs_changed_to_named{suffix}": ", ".join(f"{k} {v}" for k, v in sorted(named_pairs.items())) or "none"}


def summarize(rows: list) -> dict:
    """The flat figures of the draws (module doc, :data:`DEFINITIONS`): the headline rates over the detectable
    worlds, the same over every scored draw (``*_all_draws``), the honesty of the undetectable draws; a draw whose
    own FE failed (``worlds_failed_seeds``) has no readings and is not scored."""
    failed = [r["seed"] for r in rows if "world_failed" in r]
    scored = [r for r in rows if "world_failed" not in r]
    seen = [r for r in scored if r["detectable"]]
    unseen = [r for r in scored if not r["detectable"]]
    median = lambda k: round(float(np.median([r[k] for r in scored])), 2) if scored else None
    snr = {el: [c["snr"] for r in scored for c in r["changes"] if c["element"] == el] for el in sorted(ELEMENT.values())}
    return {"worlds_drawn": len(rows), "worlds_detectable": len(seen), "worlds_undetectable": len(unseen),
            "worlds_failed": len(failed), "worlds_failed_seeds": ", ".join(map(str, failed)) or "none",
            "seeds_drawn": f"{rows[0]['seed']}-{rows[-1]['seed']}" if rows else "none",
            **_rates(seen, ""), **_rates(scored, "_all_draws"),
            "honesty_rate_undetectable": _rate(unseen, "honest"),
            "honesty_count_undetectable": int(sum(r["honest"] for r in unseen)),
            **_confusions(seen, ""), **_confusions(scored, "_all_draws"),
            "undetectable_changed_to_named": ", ".join(
                f"{r['seed']} {_short(r['changes'])}>{'+'.join(r['named']) or 'none'}" for r in unseen) or "none",
            "snr_median_by_element": ", ".join(f"{el} {np.median(v):.2f}" for el, v in snr.items() if v),
            "cpu_per_world_s_median": median("cpu_s"), "world_fe_cpu_s_median": median("world_cpu_s"),
            "world": "device FE of the modified case (solid parts, actuation FE, frictional contact joints with "
                     "contact-FE laws), leg by leg",
            "model": "chain of the unmodified case + its idealization gap to the device FE of the unmodified case",
            "definitions": "; ".join(f"{k}: {v}" for k, v in DEFINITIONS.items()),
            "rows": rows}


def enough(rows: list, n_detectable: int) -> bool:
    """Whether ``rows`` (in seed order) hold ``n_detectable`` detectable worlds."""
    return sum(1 for r in rows if r.get("detectable")) >= n_detectable


def draw_until(one, seed: int, n_detectable: int, max_draws: int, jobs: int = 1, keep=None) -> list:
    """Rows of the worlds ``seed``, ``seed + 1``, ... up to the first prefix holding ``n_detectable`` detectable
    worlds (or ``max_draws`` draws); ``one(seed)`` gives a world's row, ``keep(row)`` sees each row in seed order.
    With ``jobs`` > 1 the worlds run in that many processes; the rows are the same prefix as with one (a world
    finished beyond it is dropped), so the result does not depend on ``jobs``."""
    rows: list = []
    keep = keep or (lambda row: None)
    if jobs <= 1:
        for s in range(seed, seed + max_draws):
            rows.append(one(s))
            keep(rows[-1])
            if enough(rows, n_detectable):
                break
        return rows
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    done: dict = {}
    with ProcessPoolExecutor(jobs) as ex:   # one world per process: each FE world and diagnosis is single-threaded
        running = {ex.submit(one, s): s for s in range(seed, seed + min(jobs, max_draws))}
        nxt = seed + len(running)
        while running and not enough(rows, n_detectable):
            finished, _ = wait(running, return_when=FIRST_COMPLETED)
            for f in finished:
                done[running.pop(f)] = f.result()
            while seed + len(rows) in done and not enough(rows, n_detectable):   # the prefix in seed order
                rows.append(done.pop(seed + len(rows)))
                keep(rows[-1])
            while len(running) < jobs and nxt < seed + max_draws and not enough(rows, n_detectable):
                running[ex.submit(one, nxt)] = nxt
                nxt += 1
        for f in running:
            f.cancel()
    return rows


def run(n_detectable: int = WORLDS, seed: int = SEED, jobs: int = 1, mesh: str = "coarse",
        detail: str = DETAIL_PATH, max_draws: int | None = None) -> dict:
    """The flat figures of the draws from ``seed`` until ``n_detectable`` detectable worlds (at most ``max_draws``,
    default :data:`MAX_DRAWS_FACTOR` x ``n_detectable``); each world's row is printed as it comes and the rows so
    far are kept in ``detail`` (JSON; a long run can be read before it ends)."""
    from functools import partial
    from femcheck.report.atomic import write_text_atomic
    max_draws = MAX_DRAWS_FACTOR * n_detectable if max_draws is None else int(max_draws)
    rows: list = []

    def keep(row, done: bool = False):
        if row is not None:
            rows.append(row)
            print(_line(row), flush=True)
        write_text_atomic(detail, json.dumps({"complete": done, "worlds": rows}, indent=2) + "\n")
    draw_until(partial(run_world, mesh=mesh), seed, n_detectable, max_draws, jobs, keep)
    keep(None, done=True)
    fig = summarize(rows)
    fig.pop("rows")
    return {"detectable_worlds_asked": n_detectable, "max_draws": max_draws,
            "detectable_worlds_reached": bool(fig["worlds_detectable"] >= n_detectable), **fig,
            "cpu_s_total": round(sum(r["cpu_s"] for r in rows), 1), "mesh": mesh, "detail_file": detail,
            "diagnosis_pin_law_radius_factors": ", ".join(f"{x:g}" for x in RADIUS_FACTORS)}


def table(figures: dict) -> str:
    """The confusion tables of the single changes (strict first named element; the first named alias group) over
    the detectable worlds, then the first named alias group over every scored draw, from the rows the run kept
    (``make bench``'s summary)."""
    rows = [r for r in json.loads(open(figures["detail_file"], encoding="utf-8").read())["worlds"]
            if "world_failed" not in r]
    seen = [r for r in rows if r["detectable"]]
    return ("detectable worlds (every change SNR >= %g):\n" % DETECTABLE_SNR + confusion_table(seen)
            + "\n\nwith the alias groups the diagnosis declares:\n" + confusion_table(seen, "first_group")
            + "\n\nall draws, with the alias groups:\n" + confusion_table(rows, "first_group"))


def _line(r: dict) -> str:
    if "world_failed" in r:
        return f"seed {r['seed']}: {_short(r['changes'])} -> world FE failed: {r['world_failed']} (not scored)"
    groups = "; ".join(" \u2261 ".join(g["members"]) for g in r.get("alias_groups", []))
    snr = ", ".join(f"{c['snr']:.1f}" for c in r["changes"])
    seen = "detectable" if r["detectable"] else ("undetectable, honest" if r["honest"] else "undetectable, WRONG NAME")
    return (f"seed {r['seed']}: {_short(r['changes'])} (SNR {snr}; {seen}) -> {', '.join(r['named']) or 'none'}"
            f"{' [' + groups + ']' if groups else ''} ({r['verdict']}, {r['cpu_s']} s CPU)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m femcheck.bench.physical_worlds", description=__doc__.split("\n")[0])
    ap.add_argument("--worlds", type=int, default=WORLDS,
                    help="detectable worlds to draw until (every draw, detectable or not, is kept and reported)")
    ap.add_argument("--max-draws", type=int, default=None,
                    help=f"stop after this many draws even short of --worlds detectable ones (default "
                         f"{MAX_DRAWS_FACTOR} x --worlds)")
    ap.add_argument("--seed", type=int, default=SEED)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--mesh", choices=("coarse", "default"), default="coarse",
                    help="mesh of the device FE's solid parts and joint contact FE (world and anchor alike)")
    ap.add_argument("--out", default="reports/bench/physical_worlds.json")
    ap.add_argument("--detail", default=DETAIL_PATH, help="each world's row (JSON)")
    a = ap.parse_args(argv)
    if a.worlds < 1 or (a.max_draws is not None and a.max_draws < a.worlds):
        print(f"--worlds {a.worlds} / --max-draws {a.max_draws}: expected --worlds >= 1 and --max-draws >= --worlds")
        return 2
    from femcheck.bench.__main__ import machine
    from femcheck.report.atomic import write_text_atomic
    t0 = time.perf_counter()
    fig = run(a.worlds, a.seed, a.jobs, a.mesh, a.detail, a.max_draws)
    command = (f"python -m femcheck.bench.physical_worlds --worlds {a.worlds} --seed {a.seed} --jobs {a.jobs}"
               f" --mesh {a.mesh}" + (f" --max-draws {a.max_draws}" if a.max_draws is not None else ""))
    fig = {"bench_wall_s": round(time.perf_counter() - t0, 3), **machine(), **fig, "command": command}
    write_text_atomic(a.out, json.dumps(fig, indent=2) + "\n")
    print(json.dumps(fig, indent=2))
    print(table(fig))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
