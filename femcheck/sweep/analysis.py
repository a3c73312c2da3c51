"""What a sweep says about the design: worst-case stiffness, elasticities, Sobol' indices, element
shares and the mass-stiffness trade-off.

Per sample s (parameter vector p_s) and load direction d the quantity of interest is the worst
stiffness over the test points (seed 000 §4.7 uses the directional stiffness over the workspace):

    k_min,d(p) = min_j F / (d . t_j(p))      (N/m; j over the swept points, "min over the cube")

and ``k_min = min_d k_min,d``. From it:

- elasticities ``e_j = d ln k / d ln p_j``: *global* by least squares of ln k_min,d on ln p over the
  whole box (``ln k = a + sum_j e_j ln p_j``, with its R^2), and *local* at the case's nominal values
  by central differences in ln p (:func:`local_elasticities`, relative step 1e-3);
- variance-based (Sobol') indices of k_min,d: first-order S_i and total S_Ti from the Saltelli design
  (``--design sobol``; estimators of Saltelli 2010 / Jansen 1999 via ``scipy.stats.sobol_indices``),
  or the exact first-order (main-effect) indices of a full factorial (``--design grid``:
  S_i = Var(E[Y | x_i]) / Var(Y) over the grid levels); an LHS design gives none;
- element shares (docs/conventions.md §7) per sample, mean over points and load directions;
- the mass of the sized elements (``mass_kg``) against k_min, with its Pareto front (lighter and stiffer
  than every other sample).
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np

from femcheck.sweep.design import BLOCK_A, BLOCK_AB, BLOCK_B
from femcheck.sweep.evaluate_analytical import AnalyticalTask, dir_tag, run_analytical_task

log = logging.getLogger(__name__)

#: relative step of the local elasticity (central difference in ln p): truncation error ~ h^2 ~ 1e-6
LOCAL_STEP = 1e-3


@dataclasses.dataclass(frozen=True)
class SweepAnalysis:
    """Per-sample figures and sensitivity tables of a sweep (SI).

    params: (m, d) values; keys; directions; k_min: {direction: (m,) N/m} (NaN where a point failed);
    k_min_all: (m,); shares: {element: (m,)}; mass_kg: (m,); ok: (m,) bool;
    elasticity: {direction: (d,)} global log-log slopes (NaN for ranges touching p <= 0); elasticity_r2:
    {direction: R^2}; sobol_first / sobol_total: {output: (d,)} or None; sobol_method: text;
    pareto: indices of the mass-stiffness Pareto front, by increasing mass.
    """

    keys: tuple[str, ...]
    directions: tuple[str, ...]
    params: np.ndarray
    k_min: dict
    k_min_all: np.ndarray
    shares: dict
    mass_kg: np.ndarray
    ok: np.ndarray
    elasticity: dict
    elasticity_r2: dict
    sobol_first: dict | None
    sobol_total: dict | None
    sobol_method: str
    pareto: np.ndarray

    def summary(self) -> dict:
        """JSON-ready summary (lists, floats)."""
        f = lambda a: None if a is None else {k: [float(x) for x in v] for k, v in a.items()}
        return {
            "keys": list(self.keys), "directions": list(self.directions), "samples": int(self.params.shape[0]),
            "samples_ok": int(self.ok.sum()),
            "k_min_N_per_m": {d: _stats(v) for d, v in self.k_min.items()} | {"all": _stats(self.k_min_all)},
            "elasticity_global": f(self.elasticity), "elasticity_r2": {k: float(v) for k, v in self.elasticity_r2.items()},
            "sobol_method": self.sobol_method, "sobol_first": f(self.sobol_first), "sobol_total": f(self.sobol_total),
            "shares": {e: _stats(v) for e, v in self.shares.items()}, "mass_kg": _stats(self.mass_kg),
            "pareto_samples": [int(i) for i in self.pareto],
        }


def _stats(v) -> dict:
    v = np.asarray(v, float)
    v = v[np.isfinite(v)]
    if not v.size:
        return {"min": None, "mean": None, "max": None}
    return {"min": float(v.min()), "mean": float(v.mean()), "max": float(v.max())}


def per_sample(table, m: int, n_pts: int, column: str) -> np.ndarray:
    """(m, n_pts) view of a result column (rows sorted by sample, all points present)."""
    return np.asarray(table.column(column).to_numpy(zero_copy_only=False), dtype=float).reshape(m, n_pts)


def analyse(outcome) -> SweepAnalysis:
    """Analyse a :class:`femcheck.sweep.run.SweepOutcome` (see the module docstring)."""
    des, ranges, table = outcome.design, outcome.ranges, outcome.table
    m, n_pts = des.m, len(outcome.points)
    ids = np.asarray(table.column("sample_id").to_numpy()).reshape(m, n_pts)
    if not np.all(ids == np.arange(m)[:, None]):
        raise ValueError("result table is not complete or not sorted by sample")
    directions = tuple(outcome.manifest["options"]["directions"])
    ok = np.asarray(table.column("ok").to_numpy(zero_copy_only=False), bool).reshape(m, n_pts).all(axis=1)
    k_min = {d: per_sample(table, m, n_pts, f"k_{dir_tag(d)}_N_per_m").min(axis=1) for d in directions}
    k_all = np.min(np.stack(list(k_min.values())), axis=0)
    # the element kinds are the table's share columns (the 6-PSU's five, or a parallel device's)
    shares = {c[len("share_"):]: per_sample(table, m, n_pts, c).mean(axis=1) for c in table.column_names
              if c.startswith("share_")}
    mass = per_sample(table, m, n_pts, "mass_kg")[:, 0]
    P = des.values
    elasticity, r2 = {}, {}
    for d, k in list(k_min.items()) + [("all", k_all)]:
        elasticity[d], r2[d] = log_log_slopes(P, k, ok)
    outputs = {**k_min, "all": k_all}
    first, total, method = sobol_indices(des, outputs, ok)
    return SweepAnalysis(keys=tuple(r.key for r in ranges), directions=directions, params=P, k_min=k_min,
                         k_min_all=k_all, shares=shares, mass_kg=mass, ok=ok, elasticity=elasticity,
                         elasticity_r2=r2, sobol_first=first, sobol_total=total, sobol_method=method,
                         pareto=pareto_front(mass, k_all, ok))


def log_log_slopes(P: np.ndarray, k: np.ndarray, ok: np.ndarray) -> tuple[np.ndarray, float]:
    """Global elasticities: least squares of ln k = a + sum_j e_j ln p_j over the samples; (e (d,), R^2).

    Parameters with a non-positive value or no spread get NaN (ln p undefined / slope not identifiable).
    """
    d = P.shape[1]
    e = np.full(d, np.nan)
    use = ok & np.isfinite(k) & (k > 0)
    if use.sum() < 2:
        return e, float("nan")
    cols = [j for j in range(d) if np.all(P[use, j] > 0) and np.ptp(np.log(P[use, j])) > 0]
    if use.sum() <= len(cols) + 1 or not cols:
        return e, float("nan")
    X = np.column_stack([np.ones(use.sum())] + [np.log(P[use, j]) for j in cols])
    y = np.log(k[use])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    e[cols] = coef[1:]
    resid = y - X @ coef
    ss = np.sum((y - y.mean()) ** 2)
    return e, float(1.0 - resid @ resid / ss) if ss > 0 else 1.0


def sobol_indices(des, outputs: dict, ok: np.ndarray):
    """First-order and total Sobol' indices per output, where the design allows (module docstring).

    Returns (first {output: (d,)} | None, total {output: (d,)} | None, method text).
    """
    d = des.values.shape[1]
    if des.kind == "sobol":
        if not ok.all():
            return None, None, "not computed: some samples failed (Saltelli estimators need every sample)"
        from scipy.stats import sobol_indices as scipy_sobol
        n = des.n_base
        Y = np.stack(list(outputs.values()))  # (s, m)
        f_A = Y[:, des.block == BLOCK_A]
        f_B = Y[:, des.block == BLOCK_B]
        f_AB = np.stack([Y[:, des.block == BLOCK_AB + i] for i in range(d)])
        res = scipy_sobol(func={"f_A": f_A, "f_B": f_B, "f_AB": f_AB}, n=n)
        names = list(outputs)
        # scipy drops the parameter axis when there is a single parameter: restore (outputs, d)
        first = np.reshape(res.first_order, (len(names), d))
        total = np.reshape(res.total_order, (len(names), d))
        return ({k: first[i] for i, k in enumerate(names)},
                {k: total[i] for i, k in enumerate(names)},
                f"Saltelli design, n = {n} base samples, {des.m} evaluations (scipy.stats.sobol_indices: "
                "Saltelli 2010 first order, Jansen 1999 total)")
    if des.kind == "grid" and d >= 1:
        if not ok.all():
            return None, None, "not computed: some grid samples failed"
        first = {}
        for name, y in outputs.items():
            var = np.var(y)
            s = np.zeros(d)
            for j in range(d):
                _, level = np.unique(des.values[:, j], return_inverse=True)
                means = np.bincount(level, weights=y) / np.bincount(level)
                s[j] = np.var(means[level]) / var if var > 0 else 0.0
            first[name] = s
        return first, None, "full-factorial main effects (exact first-order indices over the grid levels)"
    return None, None, "not available for an LHS design (use --design sobol or grid)"


def pareto_front(mass: np.ndarray, k: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Indices of the samples no other sample beats in both mass (lower) and stiffness (higher), by mass."""
    idx = np.flatnonzero(ok & np.isfinite(k) & np.isfinite(mass))
    order = idx[np.lexsort((-k[idx], mass[idx]))]
    best = -np.inf
    front = []
    for i in order:  # one pass over the samples sorted by mass (not a loop over poses)
        if k[i] > best:
            front.append(i)
            best = k[i]
    return np.array(front, dtype=int)


def local_elasticities(case, ranges, *, model: str = "detailed", joints: str | None = None, points=None,
                       step: float = LOCAL_STEP) -> dict:
    """d ln k_min,d / d ln p_j at the case's nominal values, by central differences in ln p.

    e_j = [ln k(p_j (1 + h)) - ln k(p_j (1 - h))] / [ln(1 + h) - ln(1 - h)], all other values nominal;
    one vectorized evaluation of the 2 d perturbed samples. Returns {direction | "all": (d,)} (NaN for
    a nominal value <= 0). With the min over points, the derivative is that of the point that is the
    minimum at the nominal design (k_min is only piecewise smooth).
    """
    from femcheck.kinematics.psu6 import POINT_LABELS
    points = tuple(points or POINT_LABELS)
    d = len(ranges)
    nominal = np.array([r.nominal for r in ranges])
    V = np.tile(nominal, (2 * d, 1))
    for j in range(d):
        V[2 * j, j] *= 1.0 + step
        V[2 * j + 1, j] *= 1.0 - step
    task = AnalyticalTask(case=case, keys=tuple(r.key for r in ranges), kinds=tuple(r.kind for r in ranges),
                          values=V, sample_ids=np.arange(2 * d), sample_keys=tuple(str(i) for i in range(2 * d)),
                          model=model, joints=joints or case.model.joint_rotations, points=points)
    cols = run_analytical_task(task)
    n_pts = len(points)
    out = {}
    ks = []
    for dname in case.loads.directions:
        k = np.asarray(cols[f"k_{dir_tag(dname)}_N_per_m"]).reshape(2 * d, n_pts).min(axis=1)
        ks.append(k)
        out[dname] = _central(k, nominal, step)
    out["all"] = _central(np.min(np.stack(ks), axis=0), nominal, step)
    return out


def _central(k, nominal, step):
    e = (np.log(k[0::2]) - np.log(k[1::2])) / (np.log1p(step) - np.log1p(-step))
    return np.where(nominal > 0, e, np.nan)
