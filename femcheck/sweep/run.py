"""A whole sweep, as ``femcheck sweep`` runs it: design -> keys -> skip finished -> tasks -> store.

:func:`run_sweep` is generic over the per-chunk task function (``TASK_FUNCTIONS`` maps a model to
it). The analytical models go in chunks of about :data:`CHUNK_SAMPLE_POINTS` sample-points
(:mod:`femcheck.sweep.evaluate_analytical`); ``model = "fe"`` solves the whole-device FE model, one
sample per task (:mod:`femcheck.sweep.evaluate_fe`), so the workers share the FE samples.
"""
from __future__ import annotations

import dataclasses
import datetime as _dt
import logging
import math
import time

import numpy as np

from femcheck.errors import CaseError, CheckFailedError, FemcheckError
from femcheck.sweep.design import Design, make_design
from femcheck.sweep.evaluate_analytical import AnalyticalTask, run_analytical_task
from femcheck.sweep.evaluate_fe import FE_LEVELS, FETask, fe_code_version, run_fe_task
from femcheck.sweep.executor import SweepInterrupted, run_tasks, scheduler_address
from femcheck.sweep.parameters import ParameterRange
from femcheck.sweep.store import SweepStore, code_version, sample_keys, software_versions

log = logging.getLogger(__name__)

#: model -> per-chunk task function (picklable, top level)
TASK_FUNCTIONS = {"simplified": run_analytical_task, "detailed": run_analytical_task, "fe": run_fe_task}
MODELS = ("simplified", "detailed", "fe")
#: target size of one task, in sample-points (a few seconds of the detailed model)
CHUNK_SAMPLE_POINTS = 20_000
#: samples per task of an FE sweep (one FE sample takes seconds to minutes: one per task balances best)
FE_CHUNK_SAMPLES = 1
#: an FE sweep in which fewer samples than this fraction solve is marked failed (exit 1): its statistics
#: would describe the samples that happened to converge, not the design
MIN_OK_FRACTION = 0.5


@dataclasses.dataclass(frozen=True)
class SweepOutcome:
    """A finished sweep: its folder, design, ranges, the result table (pyarrow) and the manifest."""

    store: SweepStore
    design: Design
    ranges: tuple[ParameterRange, ...]
    points: tuple[str, ...]
    table: object
    manifest: dict


def parse_points(text: str | None) -> tuple[str, ...]:
    """``cube`` (P0..P8) or a comma-separated list of labels -> tuple of labels."""
    from femcheck.kinematics.psu6 import POINT_LABELS
    if not text or text.strip().lower() == "cube":
        return POINT_LABELS
    labels = tuple(p.strip().upper() for p in text.split(",") if p.strip())
    bad = [p for p in labels if p not in POINT_LABELS]
    if bad or not labels:
        raise CaseError("--points", text, f"expected 'cube' or labels from {', '.join(POINT_LABELS)}")
    if len(set(labels)) != len(labels):
        raise CaseError("--points", text, "a point is listed twice")
    return labels


def _utc() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def preflight(case, out_dir, *, model: str, joints: str | None, resume: bool,
              fe_level: str = "detailed", mesh: str = "coarse") -> None:
    """The checks :func:`run_sweep` makes before any work (the CLI calls it before its progress bar)."""
    from femcheck.fe_device.mesh_levels import MESH_LEVELS
    if model not in TASK_FUNCTIONS:
        raise CaseError("--model", model, f"expected one of {list(MODELS)}")
    if model == "fe" and fe_level not in FE_LEVELS:
        raise CaseError("--fe-level", fe_level, f"expected one of {list(FE_LEVELS)}")
    if model == "fe" and mesh not in MESH_LEVELS:
        raise CaseError("--mesh", mesh, f"expected one of {list(MESH_LEVELS)}")
    if (joints or case.model.joint_rotations) not in ("rigid", "released"):
        raise CaseError("--joints", joints, "expected rigid or released")
    if SweepStore(out_dir).has_results() and not resume:
        raise FemcheckError(f"{out_dir} already holds sweep results; pass --resume to continue or reuse them, "
                            "or choose another --out")


def check_resumable(store: SweepStore, manifest: dict) -> None:
    """On ``--resume``: the stored sweep must be the same sweep (case, parameter ranges, model options), else
    the new manifest would silently replace the old one; names the first difference. The design may
    change (a longer Sobol' sequence reuses the samples it shares, by their keys)."""
    old = store.read_manifest()
    if old is None:
        return
    for what, new_v, old_v in (("case sha256", manifest["case"]["sha256"], old.get("case", {}).get("sha256")),
                               ("--param", manifest["parameters"], old.get("parameters")),
                               ("options", manifest["options"], old.get("options"))):
        if old_v is not None and _jsonable(new_v) != _jsonable(old_v):
            raise FemcheckError(f"{store.root}: --resume of a different sweep: {what} is {_brief(new_v)}, the stored "
                                f"sweep has {_brief(old_v)}; use the same options or another --out")


def _jsonable(v):
    import json
    return json.loads(json.dumps(v, default=str))


def _brief(v) -> str:
    import json
    text = json.dumps(_jsonable(v), sort_keys=True)
    return text if len(text) <= 160 else text[:157] + "..."


def _task(case, keys, kinds, values, sample_ids, skeys, *, model, joints, points, fe_level, mesh):
    """The task object of one chunk for ``model`` (:class:`FETask` for "fe", else :class:`AnalyticalTask`)."""
    if model == "fe":
        return FETask(case=case, keys=keys, kinds=kinds, values=values, sample_ids=sample_ids, sample_keys=skeys,
                      level=fe_level, joints=joints, points=points, mesh=mesh)
    return AnalyticalTask(case=case, keys=keys, kinds=kinds, values=values, sample_ids=sample_ids, sample_keys=skeys,
                          model=model, joints=joints, points=points)


def run_sweep(case, ranges: list[ParameterRange], out_dir, *, design: str = "lhs", samples: int | None = None,
              seed: int = 0, model: str = "detailed", joints: str | None = None, points=None,
              scheduler: str | None = None, jobs: int | None = None, resume: bool = False,
              chunk_samples: int | None = None, task_fn=None, on_progress=None, fe_level: str = "detailed",
              mesh: str = "coarse") -> SweepOutcome:
    """Run (or resume) a sweep of ``case`` over ``ranges`` into ``out_dir``; see docs/sweep.md.

    ``points``: tuple of labels (default: the cube P0..P8); ``jobs``: local worker processes (0 = in
    this process; default the CPU count); ``scheduler``: Dask address (or ``$FEMCHECK_SCHEDULER``);
    ``chunk_samples``: samples per task (default about :data:`CHUNK_SAMPLE_POINTS` sample-points for the
    analytical models, :data:`FE_CHUNK_SAMPLES` for FE); ``task_fn``: replaces the model's task function
    (tests); ``fe_level`` ("simplified" | "detailed") and ``mesh`` ("coarse" | "default" | "fine"): the FE
    level and mesh level of ``model = "fe"`` (ignored otherwise).
    """
    preflight(case, out_dir, model=model, joints=joints, resume=resume, fe_level=fe_level, mesh=mesh)
    joints = joints or case.model.joint_rotations
    points = tuple(points) if points else parse_points("cube")
    store = SweepStore(out_dir)
    started, t0 = _utc(), time.perf_counter()
    des = make_design(ranges, design, samples, seed)
    keys = tuple(r.key for r in ranges)
    options = {"model": model, "joints": joints, "points": list(points), "directions": list(case.loads.directions)}
    if model == "fe":  # only for FE, so the keys of analytical sweeps stored before FE sweeps existed still match
        options.update({"fe_level": fe_level, "mesh": mesh, "fe_code": fe_code_version()})
    version = code_version()
    skeys = sample_keys(case.sha256, keys, des.values, options, version)
    done = store.finished_keys() if resume else set()
    todo = np.array([i for i, k in enumerate(skeys) if k not in done], dtype=int)
    n_pts = len(points)
    manifest = {
        "kind": "femcheck sweep", "status": "running", "case": {"source": case.source, "sha256": case.sha256,
                                                              "name": getattr(case.meta, "name", "")},
        "parameters": [r.as_dict() for r in ranges],
        "design": {"kind": des.kind, "samples": des.m, "n_base": des.n_base, "seed": seed,
                   "levels": list(des.levels) if des.levels else None},
        "options": options, "code_version": version, "versions": software_versions(),
        "sample_points": des.m * n_pts, "resumed_with_finished_samples": int(des.m - len(todo)),
        "timing": {"started_utc": started},
    }
    if resume:
        check_resumable(store, manifest)
    store.write_manifest(manifest)
    design_cols = {"sample_id": np.arange(des.m), "sample_key": np.asarray(skeys, dtype=object),
                   "block": des.block, "base": des.base}
    design_cols.update({r.column: des.values[:, j] for j, r in enumerate(ranges)})
    store.write_design(design_cols)

    address = scheduler_address(scheduler)
    if chunk_samples is None and model == "fe":
        chunk_samples = FE_CHUNK_SAMPLES
    if chunk_samples is None:
        chunk_samples = max(1, CHUNK_SAMPLE_POINTS // n_pts)
        if not address:  # at least ~4 tasks per local worker for balance, when there is enough work
            import os
            workers = 1 if jobs == 0 else (jobs or os.cpu_count() or 1)
            chunk_samples = max(1, min(chunk_samples, math.ceil(len(todo) / (4 * max(workers, 1)))))
    kinds = tuple(r.kind for r in ranges)
    tasks = [_task(case, keys, kinds, des.values[idx], idx, tuple(skeys[i] for i in idx), model=model, joints=joints,
                   points=points, fe_level=fe_level, mesh=mesh)
             for idx in (todo[s:s + chunk_samples] for s in range(0, len(todo), chunk_samples))]
    log.info("sweep: %d samples x %d points, %d to evaluate in %d tasks", des.m, n_pts, len(todo), len(tasks))

    def stop(status: str, exc_done: int):
        manifest["status"] = status
        manifest["timing"].update({"stopped_utc": _utc(), "wall_s": time.perf_counter() - t0,
                                   "tasks_finished_this_run": exc_done, "tasks_this_run": len(tasks)})
        store.write_manifest(manifest)

    finished = [0]

    def on_result(task, result):
        store.write_chunk(result)
        finished[0] += 1

    try:
        timing = run_tasks(task_fn or TASK_FUNCTIONS[model], tasks, on_result=on_result, jobs=jobs,
                           scheduler=address, on_progress=on_progress)
    except SweepInterrupted:
        stop("interrupted", finished[0])
        raise
    except KeyboardInterrupt:
        stop("interrupted", finished[0])
        raise
    table = store.results_for(skeys, n_pts)
    if table is None:
        stop("incomplete", finished[0])
        raise FemcheckError(f"{store.root}: some samples have no result after the run; run again with --resume")
    store.write_results(table)
    wall = time.perf_counter() - t0
    n_eval = len(todo) * n_pts
    manifest["status"] = "complete"
    manifest["timing"].update({
        "finished_utc": _utc(), "wall_s": wall, "compute_wall_s": timing["wall_s"], "backend": timing["backend"],
        "workers": timing["workers"], "tasks": timing["tasks"], "sample_points_evaluated": n_eval,
        "sample_points_per_s": n_eval / timing["wall_s"] if timing["wall_s"] > 0 else None,
    })
    ok = table.column("ok").to_numpy(zero_copy_only=False)
    manifest["sample_points_ok"] = int(np.sum(ok))
    if model == "fe":
        sample_ok = ok.reshape(des.m, n_pts).all(axis=1) if ok.size == des.m * n_pts else ok
        fraction = float(np.mean(sample_ok)) if sample_ok.size else 0.0
        manifest["samples_ok_fraction"] = fraction
        if fraction < MIN_OK_FRACTION:
            failures = table.column("failure").to_pylist() if "failure" in table.column_names else []
            first = next((f for f in failures if f), "no failure text stored")
            manifest["status"] = "failed"
            manifest["first_error"] = first
            store.write_manifest(manifest)
            raise CheckFailedError(f"{store.root}: only {100 * fraction:.0f} % of the FE samples solved (at least "
                                   f"{100 * MIN_OK_FRACTION:.0f} % needed); first error: {first}")
    store.write_manifest(manifest)
    return SweepOutcome(store=store, design=des, ranges=tuple(ranges), points=points, table=table, manifest=manifest)
