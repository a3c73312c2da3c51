"""The static stiffness test protocol of seed 000 (§3.1.3 steps 3-6, §4.3.2) applied to measured readings.

Per point, direction and trial the dials are zeroed unloaded, the preload P_p is applied and delta_p read,
then the total P_p + P_T and delta_t read. The deflection due to the test load and the stiffness are
(seed 000 eq. 1)::

    delta = delta_t - delta_p,        K = P_T / delta        (along the load direction)

averaged over the trials. ``unload`` readings (back to P_p, then to 0) reveal hysteresis; an optional
``sweep`` staircase (5..30 N at P0) identifies the preload (:func:`identify_preload`, seed 000 Fig. 8).

Uncertainty: a reading is the true displacement plus noise, quantized to a reading quantum q. q is the
quantum *seen in the data* (:func:`reading_quantum`: the largest step of which every reading is a whole
multiple), or the case's dial resolution when the readings show none. The reading noise is estimated from
the trial scatter robustly against a trend over trial order: with three or more trials per state, the
residuals of a straight line over trial order fitted per state and axis, pooled over their n - 2 degrees
of freedom (a linear drift or creep is removed exactly); with two, von Neumann's mean square successive
difference ``sigma^2 = sum (x_{t+1} - x_t)^2 / (2 n_diff)``. The scatter of quantized readings contains only the
part of the rounding error that varies from trial to trial; the rest, b^2 (:func:`quantization_bias_var`, q^2/12
when the readings repeat exactly), is shared by all trials of a state. With a quantum seen in the data, one reading
has ``sigma_r^2 = s^2 + b^2`` (s^2 the trial scatter) and a state averaged over n trials ``b^2 + s^2 / n``
(:func:`mean_sigma`), not sigma_r^2 / n; a deflection (difference of two states) has twice that variance. Without a
quantum in the data, ``sigma_r^2 = max(s^2, r^2 / 12)`` for the case's dial resolution r, averaging down as 1/n. The trend itself is kept as a finding: ``trial_drift_m`` is the pooled
least-squares slope of the readings over trial order (m per trial) and ``trial_drift_sigma_m`` its standard
error. ``sigma_dof`` is the number of degrees of freedom of the scatter estimate (0 when the quantization
floor sets sigma): a goodness-of-fit test against it is an F test (lack of fit against pure error).
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np

from femcheck.errors import MeasuredDataError
from femcheck.measured.csv_format import AXIS_DIRECTIONS, MeasuredData

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class Readings:
    """Trial-averaged reading states and the per-case deflections of eq. 1 (SI).

    States (m): one per distinct (point, direction, phase, load): ``pose`` (m, 6) m/rad, ``force`` (m, 3) N,
    ``load_N`` (m,), ``phase`` (m,) str, ``peak_N`` (m,) highest load of the loading sequence before the
    state (unload states; = load otherwise), ``disp`` (m, 3) m mean reading, ``sigma`` (m, 3) m standard
    uncertainty of the mean, ``n_trials`` (m,), ``point``, ``direction`` (m,) str, ``case_index`` (m,) index of the case
    (-1 for sweep states of a direction without a preload/total test).
    Cases (c): one per (point, direction) with preload and total readings: ``case_point``, ``case_direction``
    (c,) str, ``case_unit`` (c, 3) load direction, ``case_pose`` (c, 6), ``preload_N``, ``test_N`` (c,) (P_p, P_T),
    ``delta`` (c, 3) m eq. 1 deflection averaged over trials, ``delta_sigma`` (c, 3) m, ``preload_state``,
    ``total_state`` (c,) state indices.
    """

    source: str
    pose: np.ndarray
    force: np.ndarray
    load_N: np.ndarray
    phase: np.ndarray
    peak_N: np.ndarray
    disp: np.ndarray
    sigma: np.ndarray
    n_trials: np.ndarray
    point: np.ndarray
    direction: np.ndarray
    case_index: np.ndarray
    case_point: np.ndarray
    case_direction: np.ndarray
    case_unit: np.ndarray
    case_pose: np.ndarray
    preload_N: np.ndarray
    test_N: np.ndarray
    delta: np.ndarray
    delta_sigma: np.ndarray
    preload_state: np.ndarray
    total_state: np.ndarray
    reading_sigma_m: float
    resolution_m: float
    quantum_m: float = 0.0
    trial_drift_m: float = 0.0
    trial_drift_sigma_m: float = 0.0
    sigma_dof: int = 0
    #: the raw readings behind the means (r rows): ``row_state`` (r,) state index, ``row_trial`` (r,) trial
    #: number, ``row_disp`` (r, 3) m reading; for pure-error estimates in a subspace
    #: (:mod:`femcheck.diagnose.lack_of_fit`); None when the readings were built without them
    row_state: np.ndarray | None = dataclasses.field(default=None, repr=False, compare=False)
    row_trial: np.ndarray | None = dataclasses.field(default=None, repr=False, compare=False)
    row_disp: np.ndarray | None = dataclasses.field(default=None, repr=False, compare=False)

    @property
    def n_states(self) -> int:
        return len(self.phase)

    @property
    def n_cases(self) -> int:
        return len(self.case_point)

    @property
    def points(self) -> list[str]:
        """Distinct points in first-seen order."""
        return list(dict.fromkeys(self.point.tolist()))

    def case_axis(self) -> np.ndarray:
        """(c,) the load-direction label without sign ('x', 'y', 'z' or the named load case)."""
        return np.array([d.lstrip("+-") if d in AXIS_DIRECTIONS else d for d in self.case_direction], dtype=object)

    def stiffness(self) -> np.ndarray:
        """(c,) K = P_T / delta along the load direction, N/m (seed 000 eq. 1)."""
        return self.test_N / np.einsum("ij,ij->i", self.delta, self.case_unit)


def resolve_poses(data: MeasuredData, case, pose_table: dict[str, np.ndarray] | None = None) -> np.ndarray:
    """(r, 6) pose of every row: P0..P8 from the case's test points, other ids from ``pose_table``."""
    from femcheck.kinematics.psu6 import POINT_LABELS, test_points
    table = {lab: p for lab, p in zip(POINT_LABELS, test_points(case))}
    table.update(pose_table or {})
    out = np.empty((len(data), 6))
    for i, p in enumerate(data.point):
        if p not in table:
            raise data.error(i, "point", f"{p!r} is not P0..P8 and not a pose id of the case "
                             f"(known: {', '.join(sorted(table))}; readings at a plan's poses need its JSON: "
                             "--pose-table PLAN.json)")
        out[i] = table[p]
    return out


def reading_quantum(disp: np.ndarray, floor_m: float = 1e-8) -> float:
    """The quantum q (m) of which every reading in ``disp`` is a whole multiple: the greatest common divisor
    (Euclid's algorithm with a tolerance of 1e-6 q) of the distinct reading magnitudes; 0.0 when it falls
    below ``floor_m`` (continuous readings) or the readings have fewer than two distinct values."""
    v = np.unique(np.round(np.abs(np.asarray(disp, float).ravel()), 12))
    v = v[v > 0]
    if v.size < 2:
        return 0.0
    q = float(v[0])
    for x in v[1:]:
        a, b = float(x), q
        while b > 1e-6 * max(q, floor_m) and b >= floor_m * 1e-3:
            a, b = b, a % b
            if abs(b - a) < 1e-6 * a:   # a remainder within tolerance of the divisor is zero
                b = 0.0
        q = a
        if q < floor_m:
            return 0.0
    return q if np.max(np.abs(v / q - np.round(v / q))) < 1e-4 else 0.0


def trial_scatter(idx: np.ndarray, trial: np.ndarray, disp: np.ndarray,
                  live: np.ndarray | None = None) -> tuple[float, int, float, float]:
    """Robust pooled reading variance over states ``idx`` (r,) from successive differences in ``trial`` order
    (module docstring): (variance m^2, number of differences, drift slope m / trial, its standard error).
    ``live`` (m, 3) bool: the state axes that enter the variance (default all)."""
    order = np.lexsort((trial, idx))
    i, t, x = idx[order], trial[order].astype(float), disp[order]
    m = int(i.max()) + 1 if i.size else 0
    cnt = np.bincount(i, minlength=m).astype(float)
    use = np.ones((m, x.shape[1]), bool) if live is None else np.asarray(live, bool)
    if np.all(cnt[cnt > 0] >= 3) and np.any(cnt >= 3):
        # three or more trials per state: residuals of a straight line over trial order per state, so any
        # linear trend (drift, creep) is removed before the scatter is pooled (n - 2 dof per state)
        S0, S1, S2 = cnt, np.bincount(i, t, minlength=m), np.bincount(i, t * t, minlength=m)
        det = S0 * S2 - S1 ** 2
        res2, n_diff = 0.0, int(np.sum((np.maximum(cnt, 2) - 2)[:, None] * use))
        for ax in range(x.shape[1]):
            Sy, Sty = np.bincount(i, x[:, ax], minlength=m), np.bincount(i, t * x[:, ax], minlength=m)
            with np.errstate(invalid="ignore", divide="ignore"):
                b = np.where(det > 0, (S0 * Sty - S1 * Sy) / det, 0.0)
                a0 = np.where(cnt > 0, (Sy - b * S1) / np.maximum(cnt, 1), 0.0)
            res2 += float(np.sum(((x[:, ax] - a0[i] - b[i] * t) ** 2)[use[i, ax]]))
        var = res2 / n_diff if n_diff else 0.0
    else:
        same = i[1:] == i[:-1]
        d = (x[1:] - x[:-1])[same]
        w = use[i[1:][same]]
        n_diff = int(w.sum())
        var = float(np.sum(d ** 2 * w) / (2 * n_diff)) if n_diff else 0.0
    # pooled slope over trial order: within-state centred trial number against centred reading
    tm = np.bincount(i, t, minlength=m) / np.maximum(cnt, 1)
    tc = t - tm[i]
    xm = np.zeros((m, x.shape[1]))
    np.add.at(xm, i, x)
    xc = x - xm[i] / np.maximum(cnt, 1)[i][:, None]
    # the drift of each reading along its own sign (a device creeping along the load), over the axes that read
    # anything (an axis reading zero throughout a state carries no drift information)
    live = np.abs(xm[i]) > 0
    stt = float(np.sum(tc[:, None] ** 2 * live))
    if stt <= 0:
        return var, n_diff, 0.0, 0.0
    slope = float(np.sum(tc[:, None] * xc * np.sign(xm[i]) * live) / stt)
    return var, n_diff, slope, float(np.sqrt(max(var, 1e-300) / stt))


def quantization_bias_var(noise_sigma, quantum: float):
    """Variance (m^2) of the rounding error that n repeated readings of one state share: a reading x + e (noise e ~
    N(0, sigma^2)) rounded to the step q has the mean error E_e[Q(x + e)] - x, a sawtooth in x whose Fourier
    harmonics the noise damps by exp(-2 pi^2 k^2 sigma^2 / q^2). Averaged over the state's position in the step
    (uniform), its mean square is

        b^2(sigma, q) = q^2 / (2 pi^2) sum_k exp(-4 pi^2 k^2 sigma^2 / q^2) / k^2,

    q^2 / 12 at sigma = 0 (every trial reads the same step) and 0 for sigma >> q (dithered rounding; Widrow & Kollar,
    Quantization Noise, 2008, ch. 5). It does not shrink with the number of trials."""
    K = 4096
    k = np.arange(1, K + 1)
    z = np.asarray(noise_sigma, float)[..., None] / quantum
    a = 4.0 * np.pi ** 2 * z ** 2
    # the tail beyond K: exp(-a K^2) / (K + 1/2) (sum_{k>K} 1/k^2 = 1/(K + 1/2) + O(K^-3) at sigma = 0)
    terms = np.sum(np.exp(-a * k ** 2) / k ** 2, axis=-1) + np.exp(-a[..., 0] * K ** 2) / (K + 0.5)
    out = quantum ** 2 / (2.0 * np.pi ** 2) * terms
    return float(out) if np.ndim(out) == 0 else out


def noise_sigma_from_scatter(scatter_var: float, quantum: float) -> float:
    """The noise sigma (m) before rounding to ``quantum`` whose rounded readings scatter about their own mean with the
    variance ``scatter_var`` (m^2): the within-state variance of rounded readings is sigma^2 + q^2/12 - b^2(sigma, q)
    (:func:`quantization_bias_var`), increasing in sigma; solved by bisection. 0 when the readings repeat exactly."""
    if scatter_var <= 0.0:
        return 0.0
    f = lambda s: s * s + quantum ** 2 / 12.0 - quantization_bias_var(s, quantum) - scatter_var
    lo, hi = 0.0, float(np.sqrt(scatter_var)) + quantum
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) < 0.0 else (lo, mid)
    return 0.5 * (lo + hi)


def mean_sigma(sigma_r: float, bias2: float, n_trials):
    """Standard deviation (m) of the mean of ``n_trials`` readings of one state: the scatter part
    sigma_r^2 - b^2 averages down with the trials, the rounding error they share (b^2) does not."""
    n = np.asarray(n_trials, float)
    return np.sqrt(bias2 + (sigma_r ** 2 - bias2) / n)


def process(data: MeasuredData, case, pose_table: dict[str, np.ndarray] | None = None) -> Readings:
    """Average trials, apply eq. 1 per trial and estimate uncertainties (see module docstring)."""
    poses = resolve_poses(data, case, pose_table)
    res = float(case.measurement.dial_resolution_m)
    load_key = np.round(data.load_N, 6)
    # distinct states, in file order
    keys = list(zip(data.point, data.direction, data.phase, load_key))
    state_of: dict[tuple, int] = {}
    idx = np.empty(len(data), dtype=int)
    for r, k in enumerate(keys):
        idx[r] = state_of.setdefault(k, len(state_of))
    m = len(state_of)
    first = np.array([np.flatnonzero(idx == s)[0] for s in range(m)])
    counts = np.bincount(idx, minlength=m)
    mean = np.zeros((m, 3))
    np.add.at(mean, idx, data.disp)
    mean /= counts[:, None]
    q = reading_quantum(data.disp)
    quantum = q if 0.0 < q <= res * (1 + 1e-6) or res == 0.0 else res
    # a state axis whose every trial reads zero sits within a dial step of zero, where rounding hides the scatter:
    # pooled with the others it would pull the scatter of the readings that carry the deflection down
    live = np.zeros((m, 3), bool)
    np.logical_or.at(live, idx, data.disp != 0.0)
    pooled, n_scatter, drift, drift_sd = trial_scatter(idx, np.asarray(data.trial), data.disp,
                                                       live if q > 0.0 and live.any() else None)
    sigma_r = float(np.sqrt(max(pooled, quantum ** 2 / 12.0)))
    # readings quantized to a step seen in the data: the part of the rounding error that the trials share
    bias2 = 0.0
    if q > 0.0:
        bias2 = quantization_bias_var(noise_sigma_from_scatter(pooled, q), q)
        sigma_r = float(np.sqrt(pooled + bias2))
    if sigma_r == 0.0:
        raise MeasuredDataError(data.source, None, None, "cannot estimate the reading uncertainty: a single trial and "
                                "zero dial resolution")

    # cases: (point, direction) with preload and total readings; eq. 1 per trial
    case_keys = list(dict.fromkeys(zip(data.point, data.direction)))
    c_point, c_dir, c_unit, c_pose, c_pp, c_pt, c_delta, c_dsig, c_ps, c_ts = ([] for _ in range(10))
    state_case = np.full(m, -1)
    peak = np.abs(data.load_N[first]).astype(float)
    for (p, d) in case_keys:
        rows = np.flatnonzero((data.point == p) & (data.direction == d))
        ph = data.phase[rows]
        pre, tot = rows[ph == "preload"], rows[ph == "total"]
        if len(pre) == 0 and len(tot) == 0:
            continue  # a sweep-only direction (preload identification)
        if len(pre) == 0 or len(tot) == 0:
            r = rows[0]
            raise data.error(r, "phase", f"point {p}, direction {d}: has {'total' if len(tot) else 'preload'} but no "
                             f"{'preload' if len(tot) else 'total'} reading (eq. 1 needs both per trial)")
        for group, name in ((pre, "preload"), (tot, "total")):
            if len(set(np.round(data.load_N[group], 6))) != 1:
                raise data.error(group[1], "load_N", f"point {p}, direction {d}: {name} load differs between trials")
        tp, tt = data.trial[pre], data.trial[tot]
        if sorted(tp) != sorted(tt):
            missing = sorted(set(tp) ^ set(tt))[0]
            raise data.error(rows[0], "trial", f"point {p}, direction {d}: trial {missing} lacks its preload or total reading")
        order_p, order_t = pre[np.argsort(tp)], tot[np.argsort(tt)]
        per_trial = data.disp[order_t] - data.disp[order_p]          # eq. 1, per trial
        u = data.force[order_t[0]] / max(np.linalg.norm(data.force[order_t[0]]), 1e-300)
        ci = len(c_point)
        c_point.append(p); c_dir.append(d); c_unit.append(u); c_pose.append(poses[order_t[0]])
        c_pp.append(abs(data.load_N[order_p[0]])); c_pt.append(abs(data.load_N[order_t[0]]) - abs(data.load_N[order_p[0]]))
        c_delta.append(per_trial.mean(0))
        c_dsig.append(np.full(3, np.sqrt(2.0) * mean_sigma(sigma_r, bias2, len(per_trial))))
        c_ps.append(idx[order_p[0]]); c_ts.append(idx[order_t[0]])
        sts = np.unique(idx[rows])
        state_case[sts] = ci
        unl = sts[data.phase[first[sts]] == "unload"]
        peak[unl] = abs(data.load_N[order_t[0]])
    if not c_point and not np.any(data.phase == "sweep"):
        raise MeasuredDataError(data.source, None, "phase", "no (point, direction) has both preload and total readings")
    state_sigma = np.repeat(mean_sigma(sigma_r, bias2, counts)[:, None], 3, 1)
    if bias2 > 0.0 and pooled > 0.0:
        # a state axis reading zero in every trial: a true value within a step of zero, mostly a symmetric or unloaded
        # one, whose rounding error is not the shared b^2 of a value anywhere in a step; its mean has the scatter only
        pinned = ~live
        state_sigma[pinned] = np.broadcast_to(np.sqrt(pooled / counts)[:, None], (m, 3))[pinned]
    log.debug("%s: %d states, %d cases, reading sigma %.3g m", data.source, m, len(c_point), sigma_r)
    return Readings(
        source=data.source, pose=poses[first], force=data.force[first], load_N=data.load_N[first],
        phase=data.phase[first], peak_N=peak, disp=mean, sigma=state_sigma,
        n_trials=counts, point=data.point[first], direction=data.direction[first], case_index=state_case,
        case_point=np.array(c_point, dtype=object), case_direction=np.array(c_dir, dtype=object),
        case_unit=np.array(c_unit).reshape(-1, 3), case_pose=np.array(c_pose).reshape(-1, 6), preload_N=np.array(c_pp, float),
        test_N=np.array(c_pt, float), delta=np.array(c_delta).reshape(-1, 3), delta_sigma=np.array(c_dsig).reshape(-1, 3),
        preload_state=np.array(c_ps, int), total_state=np.array(c_ts, int),
        reading_sigma_m=sigma_r, resolution_m=res, quantum_m=float(quantum), trial_drift_m=drift,
        trial_drift_sigma_m=drift_sd, sigma_dof=int(n_scatter) if pooled >= quantum ** 2 / 12.0 else 0,
        row_state=idx, row_trial=np.asarray(data.trial, int), row_disp=np.asarray(data.disp, float))


@dataclasses.dataclass(frozen=True)
class PreloadIdentification:
    """Result of :func:`identify_preload` for one direction: ``loads_N`` (k,) staircase levels, ``delta_m`` (k,)
    mean readings along the load, ``spread`` (k,) coefficient of variation of the incremental stiffnesses
    above each candidate, ``preload_N`` the identified preload (NaN if none qualifies) and ``stiffness_N_per_m``
    the mean (F_k - P_p)/(delta_k - delta_p) above it."""

    direction: str
    loads_N: np.ndarray
    delta_m: np.ndarray
    spread: np.ndarray
    preload_N: float
    stiffness_N_per_m: float


def identify_preload(readings: Readings, direction: str, tolerance: float | None = None) -> PreloadIdentification:
    """Smallest staircase load P_p above which the ratios (F_k - P_p) / (delta_k - delta_p) are constant
    (seed 000 §4.3.2, Fig. 8: "the smallest value that makes the ratios F/delta constant").

    Uses the ``sweep`` states of ``direction``. "Constant" means: the coefficient of variation of the
    ratios above the candidate is below ``tolerance`` (default: 3 x the relative reading uncertainty of the
    smallest increment, at least 2 %), and at least two increments remain.
    """
    sel = np.flatnonzero((readings.phase == "sweep") & (np.array([readings.case_direction[c] if c >= 0 else None
                                                                   for c in readings.case_index], dtype=object) == direction))
    if sel.size == 0:  # sweep-only direction: the states carry no case; match by force direction
        u = np.asarray(AXIS_DIRECTIONS.get(direction, (np.nan,) * 3), float)
        fu = readings.force / np.maximum(np.linalg.norm(readings.force, axis=1, keepdims=True), 1e-300)
        sel = np.flatnonzero((readings.phase == "sweep") & np.all(np.isclose(fu, u), axis=1))
    if sel.size < 3:
        raise MeasuredDataError(readings.source, None, "phase", f"direction {direction}: preload identification needs a "
                                f"'sweep' staircase of at least 3 load levels, found {sel.size}")
    sel = sel[np.argsort(np.abs(readings.load_N[sel]))]
    F = np.abs(readings.load_N[sel])
    u = readings.force[sel[-1]] / np.linalg.norm(readings.force[sel[-1]])
    d = readings.disp[sel] @ u
    spread = np.full(len(F), np.nan)
    ratio_mean = np.full(len(F), np.nan)
    for j in range(len(F) - 2):
        r = (F[j + 1:] - F[j]) / (d[j + 1:] - d[j])
        spread[j] = np.std(r) / abs(np.mean(r))
        ratio_mean[j] = np.mean(r)
    if tolerance is None:
        step = np.min(np.abs(np.diff(d))) if len(d) > 1 else np.inf
        tolerance = max(0.02, 3.0 * np.sqrt(2.0) * readings.sigma[sel].max() / max(step, 1e-300))
    ok = np.flatnonzero(spread <= tolerance)
    j = ok[0] if ok.size else None
    return PreloadIdentification(direction=direction, loads_N=F, delta_m=d, spread=spread,
                                 preload_N=float(F[j]) if j is not None else float("nan"),
                                 stiffness_N_per_m=float(ratio_mean[j]) if j is not None else float("nan"))
