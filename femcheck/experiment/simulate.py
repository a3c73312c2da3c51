"""Virtual stiffness experiment following seed 000's protocol (§3.1.3, §4.3.2; docs/conventions.md §9-10).

At each of the 9 test points and each load direction, for every trial: zero the dials unloaded, apply
the preload P_p and read, apply P_p + P_T and read, unload to P_p and read, unload to 0 and read. At P0 a
preload-identification staircase (5..30 N in 5 N steps) is read per direction and trial. Readings come
from the detailed analytical model (``femcheck.diagnose.model``) with the hidden effects applied, plus
Gaussian noise (sigma, per reading and axis), then quantized to the dial resolution:

    reading = r * round((d_true + N(0, sigma^2)) / r).

The hidden truth is returned separately (and written to its own JSON file by the CLI); it is never part of
the CSV.
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np

from femcheck.diagnose.effects import get_effect
from femcheck.diagnose.model import AnalyticalChainModel, predict_readings
from femcheck.kinematics.psu6 import POINT_LABELS
from femcheck.measured.csv_format import AXIS_DIRECTIONS, MeasuredData, format_measured_csv
from femcheck.measured.protocol import process

log = logging.getLogger(__name__)

ALL_DIRECTIONS = ("+x", "-x", "+y", "-y", "+z", "-z")
SWEEP_LOADS_N = (5.0, 10.0, 15.0, 20.0, 25.0, 30.0)   # seed 000 §4.3.2


def parse_effect_spec(text: str) -> tuple[str, dict[str, float]]:
    """``"ID[:param=value,...]"`` -> (id, {param: value}); the id and parameter names are validated."""
    eid, _, rest = text.strip().partition(":")
    eff = get_effect(eid.strip())
    params = {}
    for item in filter(None, (s.strip() for s in rest.split(","))):
        name, eq, val = item.partition("=")
        if not eq:
            raise KeyError(f"effect {eid}: {item!r} is not param=value")
        if name.strip() not in eff.param_names:
            raise KeyError(f"effect {eid}: unknown parameter {name.strip()!r}; expected one of {eff.param_names}")
        try:
            params[name.strip()] = float(val)
        except ValueError:
            raise KeyError(f"effect {eid}: {name.strip()} = {val!r} is not a number") from None
    return eff.id, params


@dataclasses.dataclass(frozen=True)
class VirtualExperiment:
    """``data`` the readings (as read back from CSV), ``csv_text`` the CSV, ``truth`` the hidden truth (dict)."""

    data: MeasuredData
    csv_text: str
    truth: dict


def protocol_rows(case, directions=ALL_DIRECTIONS, trials: int | None = None, sweep: bool = True,
                  preload_N: float | None = None, test_N: float | None = None):
    """The reading sequence of the protocol: lists point, direction, trial, phase, load_N and (r, 3) force."""
    trials = int(trials or case.measurement.trials)
    Pp = case.loads.detailed_preload_N if preload_N is None else preload_N
    PT = case.loads.detailed_test_N if test_N is None else test_N
    rows = []
    for t in range(1, trials + 1):
        for p in POINT_LABELS:
            for d in directions:
                for phase, load in (("preload", Pp), ("total", Pp + PT), ("unload", Pp), ("unload", 0.0)):
                    rows.append((p, d, t, phase, load))
        if sweep:
            for d in directions:
                for load in SWEEP_LOADS_N:
                    rows.append(("P0", d, t, "sweep", load))
    point, direction, trial, phase, load = (np.array(c, dtype=object) for c in zip(*rows))
    load = load.astype(float)
    force = load[:, None] * np.array([AXIS_DIRECTIONS[d] for d in direction], float)
    return point, direction, trial.astype(int), phase, load, force


def simulate(case, hidden=(), *, seed: int = 0, directions=ALL_DIRECTIONS, level: str = "detailed",
             joints: str | None = None, trials: int | None = None, sweep: bool = True,
             noise_sigma_m: float | None = None, resolution_m: float | None = None,
             model=None, rows=None, pose_table=None) -> VirtualExperiment:
    """Simulate the protocol with hidden effects.

    hidden: sequence of (effect id, {param: value}); an empty dict draws a random magnitude and location
    (``Effect.sample_truth``) from the seeded generator. ``model``: the reading model the data come from
    (default the analytical chain of ``level`` and ``joints``; e.g. the device FE with contact joints,
    :class:`femcheck.diagnose.fe_model.DeviceFEReadingModel`). ``rows``: the reading sequence to simulate instead
    of the protocol's, as (point, direction, trial, phase, load_N, force) like :func:`protocol_rows` (e.g. a plan's,
    :meth:`femcheck.diagnose.plan.Plan.protocol_rows`), with ``pose_table`` {pose id: (6,) pose} for points other
    than P0..P8. Returns a :class:`VirtualExperiment`.
    """
    rng = np.random.default_rng(seed)
    joints = joints or case.model.joint_rotations
    if model is None:
        model = AnalyticalChainModel(case, level, joints)
    else:
        level, joints = getattr(model, "level", level), model.joints
    sigma = case.measurement.noise_sigma_m if noise_sigma_m is None else noise_sigma_m
    res = case.measurement.dial_resolution_m if resolution_m is None else resolution_m
    effs, vals, truth_effects = [], [], []
    for eid, given in hidden:
        eff = get_effect(eid)
        if eff.id == "none":
            continue
        if not eff.applicable(model):
            raise ValueError(f"effect {eid} does not apply to the {model.name} model")
        params = dict(given) if given else eff.sample_truth(rng, case)
        v = eff.values_from(params, model)
        effs.append(eff)
        vals.append(v)
        truth_effects.append({"id": eff.id, "params": dict(zip(eff.param_names, map(float, v))),
                              "location": eff.location(v, None, None)})
    point, direction, trial, phase, load, force = protocol_rows(case, directions, trials, sweep) if rows is None else rows
    n = len(point)
    noiseless = MeasuredData(source="<virtual experiment>", point=point, direction=direction, trial=trial, phase=phase,
                             load_N=load, force=force, disp=np.zeros((n, 3)), row=np.arange(2, n + 2))
    states = process(noiseless, case, pose_table)
    true_state = predict_readings(model, states, effs, vals)
    key = {k: i for i, k in enumerate(zip(states.point, states.direction, states.phase, np.round(states.load_N, 6)))}
    # rows -> states (process() keys states by point, direction, phase, load)
    sidx = np.array([key[(p, d, ph, round(l, 6))] for p, d, ph, l in zip(point, direction, phase, load)])
    d_true = true_state[sidx]
    d_read = d_true + rng.normal(0.0, sigma, size=d_true.shape) if sigma > 0 else d_true.copy()
    if res > 0:
        d_read = res * np.round(d_read / res)
    text = format_measured_csv(point, direction, trial, phase, load, force, d_read, resolution_m=res,
                               meta={"case": getattr(case.meta, "name", ""), "case_sha256": case.sha256,
                                     "source": "femcheck experiment simulate"})
    from femcheck.measured.csv_format import parse_measured_csv
    data = parse_measured_csv(text, "<virtual experiment>")
    truth = {"case": case.source, "case_sha256": case.sha256, "model": level, "joints": joints,
             "source": model.name, "seed": seed,
             "effects": truth_effects or [{"id": "none", "params": {}, "location": ""}],
             "noise_sigma_m": sigma, "dial_resolution_m": res, "trials": int(trials or case.measurement.trials),
             "directions": list(directions) if rows is None else sorted(set(map(str, direction))),
             "sweep": bool(sweep) if rows is None else bool(np.any(phase == "sweep"))}
    log.debug("virtual experiment: %d readings, hidden %s", n, [e["id"] for e in truth["effects"]])
    return VirtualExperiment(data=data, csv_text=text, truth=truth)
