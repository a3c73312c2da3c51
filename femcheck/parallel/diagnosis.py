"""What the chain model of a parallel device gets wrong, located by element kind and leg (``femcheck diagnose``).

A first, small diagnosis for ``parallel_device`` cases. The 6-PSU's effect vocabulary (friction, clearance,
preload, ...) is not ported yet. It fits compliance factors of the model's elements to measured TCP
deflections. The candidate explanations are:

- ``<kind> in every leg``: one factor for one element kind (a wrong material, section or law);
- ``element kinds``: one factor per element kind, the same in every leg (several such errors);
- ``<kind> by leg``: one factor per leg for one element kind (one soft drive, one cracked rod, ...);
- ``<kind> in legs <names>``: one factor for one element kind in some legs only (the cause
  ``<kind>_in_legs``, as the 6-PSU's located effects). The leg sets are screened from the by-leg fit: the legs in
  order of how far their factor moved, the first one, the first two, ... (all legs is ``<kind> in every leg``).

Each candidate is fitted by least squares in log factors on the translations (mm). The one with the best
Bayesian information criterion ``m ln(RSS/m) + k ln m`` is kept (m readings x 3, k factors). Factors outside
``[1/(1+t), 1+t]`` are named as effects, and for a by-leg candidate the leg whose factor moved most; a kept
by-leg or in-legs candidate is the ``located`` cause (element kind, legs, factor and its 95 % interval).

The held-out error of the kept candidate is the leave-one-point-out RMS: refit without a test point's readings,
then predict them. It says whether the factors carry over to points they did not see. Readings are the
``total`` phase (minus the ``preload`` phase where both are given), averaged over trials. The model is
linearized at the measured load.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from scipy.optimize import least_squares

from femcheck.kinematics.directions import direction_unit
from femcheck.parallel.chain_model import evaluate
from femcheck.kinematics.points import POINT_LABELS, point_index, test_poses
from femcheck.parallel.leg_kinematics import solve_legs

#: a factor outside [1/(1+t), 1+t] counts as an effect
DEFAULT_THRESHOLD = 0.25
#: factors are fitted in log space inside these bounds (0.01x .. 100x the modelled compliance)
LOG_BOUND = np.log(100.0)


@dataclasses.dataclass(frozen=True)
class Readings:
    """Averaged readings: labels (m,), directions (m,) str, poses (m, 6), force (m, 3) N, disp (m, 3) m."""

    labels: tuple[str, ...]
    directions: tuple[str, ...]
    poses: np.ndarray
    force: np.ndarray
    disp: np.ndarray


def readings_from(case, data) -> Readings:
    """Average the measured rows per (point, direction); total minus preload where both phases are given."""
    P = test_poses(case)
    keys = sorted({(p, d) for p, d in zip(data.point, data.direction)})
    labels, dirs, poses, force, disp = [], [], [], [], []
    for p, d in keys:
        try:
            row = point_index([p])[0]
        except ValueError as exc:
            raise ValueError(f"{data.source}: {exc}") from None
        sel = (data.point == p) & (data.direction == d)
        tot = sel & (data.phase == "total")
        if not tot.any():
            continue
        f, u = data.force[tot].mean(0), data.disp[tot].mean(0)
        pre = sel & (data.phase == "preload")
        if pre.any():
            f, u = f - data.force[pre].mean(0), u - data.disp[pre].mean(0)
        labels.append(p), dirs.append(d), poses.append(P[row]), force.append(f), disp.append(u)
    if not labels:
        raise ValueError(f"{data.source}: no 'total' readings")
    return Readings(tuple(labels), tuple(dirs), np.array(poses), np.array(force), np.array(disp))


def predict(case, readings: Readings, scale, *, model: str, joints: str, state=None) -> np.ndarray:
    """(m, 3) modelled TCP translations (m) of the readings, element compliances scaled by ``scale`` (L, E)."""
    W = np.hstack([readings.force, np.zeros_like(readings.force)])
    r = evaluate(case.device, readings.poses, W, model=model, joints=joints, element_scale=scale, state=state)
    return r.twist[:, :3]


@dataclasses.dataclass(frozen=True)
class FitResult:
    """Fitted factors, their element kinds / legs, RMS (mm) before and after, and the held-out RMS (mm)."""

    what: str
    names: tuple[str, ...]
    factors: np.ndarray
    rms_before_mm: float
    rms_after_mm: float
    held_out_rms_mm: float
    #: 95 % intervals (low (k,), high (k,)) of the factors: log factor +- 1.96 standard errors of the least squares
    #: (Jacobian at the optimum, residual variance rss / (readings - k))
    factors_ci: tuple = ()


@dataclasses.dataclass(frozen=True)
class ParallelDiagnosis:
    """The kept candidate (``best``), every candidate's fit (``candidates``), the named ``effects``
    [(element kind or leg, factor)] and, for a by-leg candidate, the ``leg`` (name, factor)."""

    best: FitResult
    candidates: tuple[FitResult, ...]
    effects: tuple[tuple[str, float], ...]
    leg: tuple[str, float] | None
    #: (L, E) element compliance factors of the kept candidate (what its "after" predictions use) and their 95 %
    #: intervals (low (L, E), high (L, E)); cells the candidate does not fit are 1
    scale: np.ndarray | None = None
    scale_ci: tuple = ()
    #: the located cause of a kept by-leg or in-legs candidate: {"cause": "<kind>_in_legs", "element", "legs",
    #: "factor", "factor_ci"} (by leg: the legs whose factor moved beyond the threshold, the largest factor)
    located: dict | None = None

    def as_json(self) -> dict:
        def fit(f):
            return {"what": f.what, "factors": dict(zip(f.names, map(float, f.factors))),
                    "rms_before_mm": f.rms_before_mm, "rms_after_mm": f.rms_after_mm,
                    "held_out_rms_mm": f.held_out_rms_mm}
        return {"best": fit(self.best), "candidates": [fit(c) for c in self.candidates],
                "effects": [{"name": e, "factor": float(v)} for e, v in self.effects],
                "leg": None if self.leg is None else {"name": self.leg[0], "factor": float(self.leg[1])},
                "located": self.located}


def _fit(case, rd: Readings, expand, n_par, *, model, joints, state, held_out: bool):
    """Least squares in log factors; ``expand(theta) -> (L, E)`` scale.
    Returns (theta, rms_before, rms_after, held-out rms or NaN, rss)."""
    def residual(theta, rows=None):
        if rows is None:
            sub, st = rd, state
        else:
            sub = Readings(tuple(rd.labels[i] for i in rows), tuple(rd.directions[i] for i in rows), rd.poses[rows],
                           rd.force[rows], rd.disp[rows])
            st = None
        return 1e3 * (predict(case, sub, expand(theta), model=model, joints=joints, state=st) - sub.disp).ravel()

    rms = lambda r: float(np.sqrt(np.mean(r**2)))
    r0 = residual(np.zeros(n_par))
    sol = least_squares(residual, np.zeros(n_par), bounds=(-LOG_BOUND, LOG_BOUND))
    held = []
    labels = np.array(rd.labels)
    for p in (sorted(set(rd.labels)) if held_out else ()):
        keep, out = np.flatnonzero(labels != p), np.flatnonzero(labels == p)
        if keep.size:
            s = least_squares(lambda th: residual(th, keep), sol.x, bounds=(-LOG_BOUND, LOG_BOUND))
            held.append(residual(s.x, out))
    rss = float(sol.fun @ sol.fun)
    se = np.sqrt(np.clip(np.diag(np.linalg.pinv(sol.jac.T @ sol.jac)), 0, None) * rss / max(sol.fun.size - n_par, 1))
    return sol.x, rms(r0), rms(sol.fun), (rms(np.concatenate(held)) if held else float("nan")), rss, se


def diagnose(case, data, *, model: str = "detailed", joints: str | None = None,
             threshold: float = DEFAULT_THRESHOLD) -> ParallelDiagnosis:
    """Fit every candidate, keep the best by BIC, name its effects (module docstring)."""
    joints = joints or case.model.joint_rotations
    rd = readings_from(case, data)
    dev = case.device
    names = dev.element_names
    L, E = dev.n_legs, len(names)
    state = solve_legs(dev, rd.poses)
    # kinds the model level does not contain (the drive and joints in the simplified model) have nothing to fit
    present = [j for j, n in enumerate(names) if model == "detailed" or n not in ("drive", "hertz_point", "hertz_line",
                                                                                        "measured_law")]

    def by_kind(theta):
        s = np.ones((L, E))
        s[:, present] = np.exp(theta)[None, :]
        return s

    def by_leg(j):
        def expand(theta):
            s = np.ones((L, E))
            s[:, j] = np.exp(theta)
            return s
        return expand

    def one_kind(j):
        def expand(theta):
            s = np.ones((L, E))
            s[:, j] = np.exp(theta[0])
            return s
        return expand

    def in_legs(j, legs):
        def expand(theta):
            s = np.ones((L, E))
            s[legs, j] = np.exp(theta[0])
            return s
        return expand

    specs = [(f"{names[j]} in every leg", (names[j],), one_kind(j), 1) for j in present]
    specs += [("element kinds", tuple(names[j] for j in present), by_kind, len(present))]
    specs += [(f"{names[j]} by leg", tuple(lg.name for lg in dev.legs), by_leg(j), L) for j in present]
    m = 3 * len(rd.labels)
    fits, scores = [], []

    def run(what, fnames, expand, k):
        th, r0, r1, _, rss, se = _fit(case, rd, expand, k, model=model, joints=joints, state=state, held_out=False)
        fits.append((what, fnames, expand, k, th, r0, r1, se))
        scores.append(m * np.log(max(rss, 1e-300) / m) + k * np.log(m))
        return th

    for spec in specs:
        th = run(*spec)
        if spec[0].endswith(" by leg"):   # screen the leg sets: the legs in order of how far their factor moved
            j = names.index(spec[0].removesuffix(" by leg"))
            order = list(np.argsort(-np.abs(th), kind="stable"))
            for n in range(1, L):
                legs = sorted(order[:n])
                run(f"{names[j]} in legs {','.join(dev.legs[i].name for i in legs)}", (names[j],), in_legs(j, legs), 1)
    what, fnames, expand, k, th, r0, r1, se = fits[int(np.argmin(scores))]
    _, _, _, held, _, _ = _fit(case, rd, expand, k, model=model, joints=joints, state=state, held_out=True)
    best = FitResult(what, fnames, np.exp(th), r0, r1, held, (np.exp(th - 1.96 * se), np.exp(th + 1.96 * se)))
    candidates = tuple(FitResult(w, n, np.exp(t), a, b, float("nan")) for w, n, _, _, t, a, b, _ in fits)
    effects = tuple((n, float(np.exp(t))) for n, t in zip(fnames, th) if abs(t) > np.log1p(threshold))
    leg, located = None, None
    if what.endswith(" by leg") and effects:
        i = int(np.argmax(np.abs(th)))
        leg = (fnames[i], float(np.exp(th[i])))
        located = {"cause": f"{what.removesuffix(' by leg')}_in_legs", "element": what.removesuffix(" by leg"),
                   "legs": [n for n, _ in effects], "factor": leg[1],
                   "factor_ci": [float(np.exp(th[i] - 1.96 * se[i])), float(np.exp(th[i] + 1.96 * se[i]))]}
    elif " in legs " in what and effects:
        kind, legs = what.split(" in legs ")
        located = {"cause": f"{kind}_in_legs", "element": kind, "legs": legs.split(","), "factor": float(np.exp(th[0])),
                   "factor_ci": [float(np.exp(th[0] - 1.96 * se[0])), float(np.exp(th[0] + 1.96 * se[0]))]}
        if len(located["legs"]) == 1:
            leg = (located["legs"][0], located["factor"])
        effects = tuple((n, located["factor"]) for n in located["legs"])
    return ParallelDiagnosis(best=best, candidates=candidates, effects=effects, leg=leg, scale=expand(th),
                             scale_ci=(expand(th - 1.96 * se), expand(th + 1.96 * se)), located=located)


def scale_problem(case, readings: Readings, *, model: str, joints: str) -> str | None:
    """The unit slip the readings look like when their median deflection along the load is more than 10x off the
    model's as given (:func:`femcheck.diagnose.plausibility.scale_check`), else None."""
    from femcheck.diagnose.plausibility import scale_check
    unit = readings.force / np.maximum(np.linalg.norm(readings.force, axis=1, keepdims=True), 1e-300)
    pred = predict(case, readings, np.ones((case.device.n_legs, len(case.device.element_names))), model=model,
                   joints=joints)
    along = lambda d: np.einsum("ij,ij->i", d, unit)
    return scale_check(along(readings.disp), along(pred))[1]


def simulate(case, scale, *, points=POINT_LABELS, directions=None, model: str = "detailed", joints: str | None = None,
             noise_m: float = 0.0, seed: int = 0):
    """A virtual experiment: the model with element factors ``scale`` (L, E) as the 'true' device; returns the
    arguments of :func:`femcheck.measured.csv_format.format_measured_csv` (one ``total`` reading per point and
    direction under the case's test force; Gaussian noise ``noise_m`` on the dials)."""
    joints = joints or case.model.joint_rotations
    directions = tuple(directions or case.loads.directions)
    rng = np.random.default_rng(seed)
    pts, dirs, force = [], [], []
    for p in points:
        for d in directions:
            pts.append(p), dirs.append(d), force.append(case.loads.test_N * direction_unit(d))
    force = np.array(force)
    rd = Readings(tuple(pts), tuple(dirs), test_poses(case, pts), force,
                  np.zeros_like(force))
    disp = predict(case, rd, scale, model=model, joints=joints) + rng.normal(0.0, noise_m, force.shape)
    n = len(pts)
    return (np.array(pts), np.array(dirs), np.ones(n, int), np.array(["total"] * n), np.full(n, case.loads.test_N),
            force, disp)
