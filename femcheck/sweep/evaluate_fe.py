"""The FE sweep task: whole-device FE samples (``femcheck sweep --model fe``), one task per sample.

For each sample (a parameter vector p) a re-validated case variant ``case.with_params(**p)`` is
built and the device FE model (:func:`femcheck.verify.fe.run_fe`: link and guideway super-elements,
joints, rigid platform, load protocol of ``loads.py``) is solved at the task's test points for one FE
level. All swept keys go through the case variant: the FE meshes the parts from the case, so there is
no vectorized "array" route as in the analytical task. Per (sample, point) and load direction d of
the case (``[loads] directions``) the rows hold the same columns as the analytical sweep
(:func:`femcheck.sweep.evaluate_analytical.result_columns`), so the store, the analysis and the report
read both alike:

- ``k_<dir>_N_per_m = P_T / δ``: seed 000 eq. 1 with the FE deflection δ = d . t (m) under the
  protocol of the FE level (simplified: P_T = ``loads.simplified_test_N`` alone; detailed: preload
  P_p, then P_p + P_T with P_T = ``loads.detailed_test_N``, δ = t(P_p + P_T) - t(P_p));
  ``defl_<dir>_m = δ``;
- ``share_<element>``: the FE element shares of the incremental strain energy (order lg, act, sp,
  prox, uj, as docs/conventions.md §7), mean over the load directions;
- ``mass_kg``: :func:`femcheck.sweep.evaluate_analytical.element_mass_kg` of the variant (the same
  closed form as the analytical sweep: it ranks designs, it is not an FE quantity);
- ``ok``: False where the sample could not be evaluated (invalid variant, meshing failure, singular
  or non-converged solve, non-finite deflection); its numbers are NaN at all its points;
- ``failure``: the error text of a failed sample, "" otherwise (FE sweeps only; analytical sweeps
  only log it).

Every numeric column is filled by the FE for an evaluated sample; none is left NaN.

Cost: one sample solves one link super-element and 6 guideway super-elements per point (coarse mesh:
about 15-20 s for one point on one core of the development machine, almost all in the link: about
88,000 DOFs). Samples are independent, so the sweep parallelizes over samples (one task per sample,
``run_fe(..., jobs=1)`` inside each task); see docs/sweep.md.
"""
from __future__ import annotations

import dataclasses
import functools
import logging
from pathlib import Path

import numpy as np

from femcheck.errors import FemcheckError
from femcheck.sweep.evaluate_analytical import dir_tag, element_mass_kg, result_columns
from femcheck.sweep.sample_chunk import SampleChunk

log = logging.getLogger(__name__)

#: FE levels (load protocol and joint model of ``femcheck.fe_device``)
FE_LEVELS = ("simplified", "detailed")
#: part model of the FE: solid tetrahedral parts (the verification's model)
FE_KIND = "solid"
#: errors that mark one FE sample as failed instead of stopping the sweep: femcheck's own (invalid
#: variant, meshing, convergence, unreachable point), singular dense algebra, and the ValueError /
#: RuntimeError the sparse solvers raise for a singular or badly conditioned stiffness matrix


def is_sample_error(exc: BaseException) -> bool:
    """Whether ``exc`` is a failure of one sample (kept as ok = False) rather than a bug (which must stop the
    sweep): femcheck's own errors, singular algebra, and the sparse solvers' RuntimeError for a singular
    matrix - not NotImplementedError or other RuntimeErrors, nor the ValueError/TypeError of a bug."""
    if isinstance(exc, (FemcheckError, np.linalg.LinAlgError, ArithmeticError)):
        return True
    return type(exc) is RuntimeError and "singular" in str(exc).lower()

#: sources whose content defines the FE results, in addition to the analytical ones of
#: :func:`femcheck.sweep.store.code_version` (paths relative to the folder holding ``femcheck``)
_FE_SOURCES = ("femcheck/fe", "femcheck/fe_device", "femcheck/verify/fe.py", "femcheck/sweep/evaluate_fe.py",
               "geometry")


@functools.lru_cache(maxsize=1)
def fe_code_version() -> str:
    """SHA-256 (12 hex) of the FE, device-FE, meshing and FE-task sources; part of an FE sample's key,
    so a change of the FE code invalidates stored FE samples instead of mixing them in on ``--resume``."""
    import femcheck
    from femcheck.sweep.store import source_hash
    return source_hash(Path(femcheck.__file__).resolve().parent.parent, _FE_SOURCES)


@dataclasses.dataclass(frozen=True)
class FETask(SampleChunk):
    """One task of an FE sweep: one (or a few) samples (picklable; sent to pool or Dask workers).

    case: the base case; keys, kinds: swept dotted keys and their kinds (every key goes through a
    case variant here, whatever its kind); values: (k, d) parameter values (SI); sample_ids: (k,) int;
    sample_keys: (k,) result keys; level: FE level "simplified" | "detailed"; joints: "rigid" |
    "released"; points: test point labels; mesh: mesh level "coarse" | "default" | "fine".
    """

    level: str
    joints: str
    points: tuple[str, ...]
    mesh: str = "coarse"


def fe_variant(task: FETask, i: int):
    """The case variant of sample ``i`` of ``task`` (raises CaseError for invalid values)."""
    return task.case.with_params(**{key: float(task.values[i, j]) for j, key in enumerate(task.keys)})


def sample_rows(variant, fe, level: str, joints: str, points) -> dict[str, np.ndarray]:
    """The result columns (module docstring) of one solved sample: ``fe`` a
    :class:`femcheck.verify.fe.FEVerification` of ``variant``; returns column -> (n_points,) array."""
    from femcheck.chain import ELEMENT_NAMES, ELEMENTS
    n = len(points)
    out: dict[str, np.ndarray] = {}
    shares = np.zeros((n, len(ELEMENTS)))
    for dname in variant.loads.directions:
        cases = [fe.results[p].cases[(level, joints, dname)] for p in points]
        defl = np.array([c.deflection_m for c in cases])
        out[f"k_{dir_tag(dname)}_N_per_m"] = np.array([c.load_N for c in cases]) / defl
        out[f"defl_{dir_tag(dname)}_m"] = defl
        shares += np.nan_to_num(np.stack([c.contributions for c in cases]))
    shares /= len(variant.loads.directions)
    for j, e in enumerate(ELEMENTS):
        out[f"share_{ELEMENT_NAMES[e]}"] = shares[:, j]
    out["mass_kg"] = np.full(n, float(element_mass_kg(variant)))
    return out


def run_fe_task(task: FETask) -> dict[str, np.ndarray]:
    """Solve the FE model of each sample of ``task``; the columns of its rows (k samples x n points,
    sample-major), as :func:`femcheck.sweep.evaluate_analytical.run_analytical_task` returns them, plus
    ``failure``. A failing sample (:func:`is_sample_error`) gives ok = False rows with its error text."""
    from femcheck.verify.fe import run_fe
    if task.level not in FE_LEVELS:
        raise FemcheckError(f"FE level {task.level!r}: expected one of {list(FE_LEVELS)}")
    n_pts, k = len(task.points), task.n_samples
    cols = result_columns(task.keys, task.case.loads.directions)
    table = {c: np.full(k * n_pts, np.nan) for c in cols[len(task.keys):]}
    ok = np.zeros(k * n_pts, dtype=bool)
    failure = np.full(k * n_pts, "", dtype=object)
    for i in range(k):
        rows = slice(i * n_pts, (i + 1) * n_pts)
        sid = int(task.sample_ids[i])
        try:
            variant = fe_variant(task, i)
        except Exception as exc:
            if not is_sample_error(exc):
                raise
            failure[rows] = f"invalid case variant: {exc}"
            log.warning("FE sample %d not evaluated: invalid case variant: %s", sid, exc)
            continue
        try:
            fe = run_fe(variant, task.points, levels=(task.level,), mesh=task.mesh, jobs=1, kind=FE_KIND)
            block = sample_rows(variant, fe, task.level, task.joints, task.points)
        except Exception as exc:
            if not is_sample_error(exc):
                raise
            failure[rows] = f"FE failed: {type(exc).__name__}: {exc}"
            log.warning("FE sample %d not evaluated: %s: %s", sid, type(exc).__name__, exc)
            continue
        finite = all(np.all(np.isfinite(block[f"defl_{dir_tag(d)}_m"])) for d in variant.loads.directions)
        if not finite:
            failure[rows] = "FE gave a non-finite deflection"
            log.warning("FE sample %d: non-finite deflection; marked ok = False", sid)
            continue
        for c, v in block.items():
            table[c][rows] = v
        ok[rows] = True
        log.debug("FE sample %d: %.1f s (%s)", sid, fe.timings_s["wall"], fe.timings_s)

    return task.result_rows(task.points, table, ok, failure=failure)
