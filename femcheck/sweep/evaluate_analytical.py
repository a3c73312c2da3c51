"""The analytical sweep task: one chunk of samples x test points, evaluated vectorized.

For each sample (a parameter vector p) and test point P_j, and each load direction d of the case
(``[loads] directions``), the chain model (:func:`femcheck.chain.evaluate`, seed 000 §4.1-4.4,
docs/conventions.md §4-7) is evaluated under the wrench F d with F the model's test load
(``loads.detailed_test_N`` for the detailed model, ``loads.simplified_test_N`` for the simplified one;
the detailed model's Hertz contacts are linearized at that load). Stored per (sample, point):

- ``k_<dir>_N_per_m = F / (d . t)``: the stiffness along d as the paper measures it (seed 000 eq. 1,
  K = P_T / delta), t = TCP twist (m, rad); ``defl_<dir>_m = d . t``;
- ``share_<element>``: element shares of the deflection energy (docs/conventions.md §7), mean over the
  load directions (the §7 reference metric);
- ``mass_kg``: the mass of the sized elements (:func:`element_mass_kg`), per sample;
- ``ok``: False where the sample could not be evaluated (unreachable point, no convergence); its
  numbers are NaN.

Array-type parameters (see :mod:`femcheck.sweep.parameters`) go in one call for all samples x points
through ``device_parameters(case, overrides)`` with (k n_points,) arrays; variant-type parameters
group the samples by their variant values and build one ``case.with_params`` variant per group, each
group again vectorized over its samples x points. There is no Python loop per pose.
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np

from femcheck.errors import FemcheckError
from femcheck.kinematics.directions import direction_unit
from femcheck.sweep.sample_chunk import SampleChunk

log = logging.getLogger(__name__)

MODELS = ("simplified", "detailed")


def dir_tag(direction: str) -> str:
    """Column tag of a load direction: '+x' -> 'x', '-x' -> 'negx'."""
    return ("neg" if direction.startswith("-") else "") + direction.lstrip("+-")


dir_vector = direction_unit  # '+x' | '-y' | ... -> unit 3-vector (femcheck.kinematics.directions)


@dataclasses.dataclass(frozen=True)
class AnalyticalTask(SampleChunk):
    """One chunk of an analytical sweep (:class:`SampleChunk` fields, then) model: "simplified" |
    "detailed"; joints: "rigid" | "released" | None (case default); points: test point labels
    (e.g. ("P0", ..., "P8")).
    """

    model: str
    joints: str | None
    points: tuple[str, ...]


def element_mass_kg(case, overrides: dict[str, np.ndarray] | None = None) -> np.ndarray | float:
    """Mass of the sized structural elements of the 6 chains (kg), vectorized over ``overrides``.

    m = 6 [rho_lg b h L_rail + rho_pl pi (D^2 - d^2)/4 L2 + rho_ball (4/3) pi R_ball^3 + 2 rho_pin pi r_pin^2 L_u]:
    guideway bars over the usable rail length, proximal-link tubes, balls, and the two cross pins of each
    U joint (span L_u). Motors, cables, sliders, platform and base are not included: the figure ranks designs
    by the mass the swept sizes add, it is not the device mass. Densities: ``[materials.NAME] density_kg_m3``.
    """
    o = overrides or {}
    get = lambda key, value: np.asarray(o[key], float) if key in o else value
    g, gw, pl, sj, uj = case.geometry, case.guideway, case.proximal_link, case.spherical_joint, case.universal_joint
    m_lg = gw.material.density_kg_m3 * get("guideway.width_radial_m", gw.width_radial_m) \
        * get("guideway.depth_tangential_m", gw.depth_tangential_m) * g.rail_length_m
    D, d = get("proximal_link.outer_diameter_m", pl.outer_diameter_m), get("proximal_link.inner_diameter_m", pl.inner_diameter_m)
    m_pl = pl.material.density_kg_m3 * np.pi * (D**2 - d**2) / 4.0 * g.proximal_link_length_m
    m_ball = sj.ball_material.density_kg_m3 * 4.0 / 3.0 * np.pi * get("spherical_joint.ball_radius_m", sj.ball_radius_m) ** 3
    m_pin = 2.0 * uj.pin_material.density_kg_m3 * np.pi * get("universal_joint.pin_radius_m", uj.pin_radius_m) ** 2 \
        * get("universal_joint.pin_span_m", uj.pin_span_m)
    return 6.0 * (m_lg + m_pl + m_ball + m_pin)


def element_names(case) -> tuple[str, ...]:
    """The element kinds whose shares a sweep stores: the 6-PSU's five, or a parallel device's."""
    if getattr(case, "kind", "haptic_6psu") == "parallel_device":
        return case.device.element_names
    from femcheck.chain import ELEMENT_NAMES, ELEMENTS
    return tuple(ELEMENT_NAMES[e] for e in ELEMENTS)


def result_columns(keys, directions, names=None) -> list[str]:
    """Names of the numeric result columns, in table order (after sample_id, sample_key, point); ``names``:
    the element kinds (default the 6-PSU's)."""
    if names is None:
        from femcheck.chain import ELEMENT_NAMES, ELEMENTS
        names = [ELEMENT_NAMES[e] for e in ELEMENTS]
    cols = [f"p:{k}" for k in keys]
    for dname in directions:
        cols += [f"k_{dir_tag(dname)}_N_per_m", f"defl_{dir_tag(dname)}_m"]
    cols += [f"share_{n}" for n in names] + ["mass_kg"]
    return cols


def _parallel_block(case, poses, model, joints):
    """:func:`_evaluate_block` for a ``parallel_device`` case (every swept key is a case variant here)."""
    from femcheck.parallel.chain_model import evaluate
    from femcheck.parallel.leg_kinematics import solve_legs
    dev = case.device
    state = solve_legs(dev, poses)
    if not state.ok.all():
        raise FemcheckError(f"{int((~state.ok).sum())} of {len(poses)} poses not reachable by the legs")
    F = case.loads.test_N
    out = {}
    shares = np.zeros((poses.shape[0], len(dev.element_names)))
    for dname in case.loads.directions:
        dvec = dir_vector(dname)
        r = evaluate(dev, poses, np.concatenate([F * dvec, np.zeros(3)]), model=model,
                     joints=joints or case.model.joint_rotations, state=state)
        defl = r.twist[:, :3] @ dvec
        out[f"k_{dir_tag(dname)}_N_per_m"] = F / defl
        out[f"defl_{dir_tag(dname)}_m"] = defl
        shares += np.nan_to_num(r.contributions)
    shares /= len(case.loads.directions)
    for j, name in enumerate(dev.element_names):
        out[f"share_{name}"] = shares[:, j]
    out["mass_kg"] = np.full(poses.shape[0], parallel_mass_kg(case))
    return out


def parallel_mass_kg(case) -> float:
    """Mass of the links of a parallel device at its home pose (kg): density x section area x length, every leg.
    Drives, joints and the platform are not included (the figure ranks designs by the mass the sizes add)."""
    m = 0.0
    for leg, spec in zip(case.device.legs, case.legs * case.symmetry.copies):
        for ln, ls in zip(leg.links, spec.links):
            if ln.section is not None:
                m += ls.material.density_kg_m3 * float(ln.section.A) * float(np.linalg.norm(
                    leg.centres[ln.end] - leg.centres[ln.start]))
    return m


def _evaluate_block(case, poses, n_pts, overrides, model, joints):
    """(k n_pts) rows for one case (variant): stiffness/deflection per direction, mean shares.

    Returns dict column -> (k n_pts,) array. Raises femcheck/LinAlg errors for the caller to isolate.
    """
    if getattr(case, "kind", "haptic_6psu") == "parallel_device":
        return _parallel_block(case, poses, model, joints)
    from femcheck.chain import ELEMENT_NAMES, ELEMENTS, device_parameters, evaluate
    k = len(next(iter(overrides.values()))) // n_pts if overrides else poses.shape[0] // n_pts
    params = device_parameters(case, overrides) if overrides else None
    F = case.loads.detailed_test_N if model == "detailed" else case.loads.simplified_test_N
    out = {}
    shares = np.zeros((poses.shape[0], len(ELEMENTS)))
    for dname in case.loads.directions:
        dvec = dir_vector(dname)
        W = np.concatenate([F * dvec, np.zeros(3)])
        r = evaluate(case, poses, W, model=model, joints=joints, params=params)
        defl = r.twist[:, :3] @ dvec
        out[f"k_{dir_tag(dname)}_N_per_m"] = F / defl
        out[f"defl_{dir_tag(dname)}_m"] = defl
        shares += np.nan_to_num(r.contributions)
    shares /= len(case.loads.directions)
    for j, e in enumerate(ELEMENTS):
        out[f"share_{ELEMENT_NAMES[e]}"] = shares[:, j]
    out["mass_kg"] = np.broadcast_to(element_mass_kg(case, overrides), (k * n_pts,)).astype(float) \
        if overrides else np.full(k * n_pts, float(element_mass_kg(case)))
    return out


def run_analytical_task(task: AnalyticalTask) -> dict[str, np.ndarray]:
    """Evaluate one chunk; returns the columns of its rows (k samples x n points, sample-major).

    Columns: sample_id, sample_key, point, ``p:<key>`` ..., the result columns of the module docstring, ok.
    """
    from femcheck.kinematics.points import point_index
    if getattr(task.case, "kind", "haptic_6psu") == "parallel_device":
        from femcheck.parallel.device import test_points
    else:
        from femcheck.kinematics.psu6 import test_points
    if task.model not in MODELS:
        raise FemcheckError(f"model {task.model!r}: not an analytical model; expected one of {list(MODELS)}")
    case = task.case
    P_all = test_points(case)
    idx = point_index(task.points)
    n_pts, k = len(idx), task.n_samples
    array_cols = [j for j, kind in enumerate(task.kinds) if kind == "array"]
    variant_cols = [j for j, kind in enumerate(task.kinds) if kind == "variant"]
    cols = result_columns(task.keys, case.loads.directions, element_names(case))
    table = {c: np.full(k * n_pts, np.nan) for c in cols[len(task.keys):]}
    ok = np.ones(k * n_pts, dtype=bool)
    failures: list[tuple[int, str]] = []

    if variant_cols:
        _, group = np.unique(task.values[:, variant_cols], axis=0, return_inverse=True)
        group = np.asarray(group).reshape(-1)
    else:
        group = np.zeros(k, dtype=int)
    for g in np.unique(group):
        rows = np.flatnonzero(group == g)
        try:
            case_g = case.with_params(**{task.keys[j]: float(task.values[rows[0], j]) for j in variant_cols}) \
                if variant_cols else case
        except FemcheckError as exc:
            failures += [(int(task.sample_ids[r]), f"invalid case variant: {exc}") for r in rows]
            ok[(rows[:, None] * n_pts + np.arange(n_pts)).ravel()] = False
            continue
        P = (test_points(case_g) if variant_cols else P_all)[idx]
        _fill(table, ok, case_g, task, rows, P, array_cols, failures)
    if failures:
        log.info("%d of %d samples not evaluated (marked ok = False), e.g. sample %d: %s",
                    len(failures), k, failures[0][0], failures[0][1])

    return task.result_rows(task.points, table, ok)


def _fill(table, ok, case_g, task, rows, P, array_cols, failures):
    """Evaluate the samples ``rows`` of one case variant into ``table``; isolate failing samples.

    A sample with any failing point (unreachable, no convergence) is marked not ok at all its points:
    its worst case over the points is undefined."""
    n_pts = P.shape[0]
    row_idx = (rows[:, None] * n_pts + np.arange(n_pts)).ravel()
    overrides = {task.keys[j]: np.repeat(task.values[rows, j], n_pts) for j in array_cols}
    poses = np.tile(P, (len(rows), 1))
    try:
        block = _evaluate_block(case_g, poses, n_pts, overrides, task.model, task.joints)
    except (FemcheckError, np.linalg.LinAlgError) as exc:
        if len(rows) == 1:
            log.debug("sample %d: not evaluated: %s", int(task.sample_ids[rows[0]]), exc)
            failures.append((int(task.sample_ids[rows[0]]), str(exc)))
            ok[row_idx] = False
            return
        log.debug("block of %d samples failed (%s); evaluating them one by one", len(rows), exc)
        for r in rows:
            _fill(table, ok, case_g, task, np.array([r]), P, array_cols, failures)
        return
    for c, v in block.items():
        table[c][row_idx] = v
