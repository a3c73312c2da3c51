"""Self-weight diagnosis of a serial robot (a kinematic tree) from measured absolute marker positions.

1. *Before*: the model as given (its nominal springs, rigid where none) with its nuisance parameters (sensor
   frame, marker offsets, geometry; :mod:`femcheck.robot.measurement_model`) calibrated by Gauss-Newton with the
   stated weak prior.
2. At that point every nuisance direction and every elastic direction of the vocabulary
   (:mod:`femcheck.robot.causes`) is linearized (forward differences of the full model, fixed-point passes
   included). Every rival explanation -- none, each cause (in its best placement), each pair -- is then a linear
   least-squares problem with bounds: the nuisance block is projected out (variable projection, Golub &
   Pereyra 1973) and the few cause parameters are solved with bounds (``scipy.optimize.lsq_linear``).
3. The rivals are weighed by :mod:`femcheck.diagnose.evidence` (BIC posteriors, goodness of fit against sigma,
   ambiguity, verdict).
4. *After*: the leading explanation refitted on the full nonlinear model (modified Newton: the linearized
   Jacobian, the exact residual), its parameters with 95 % intervals.
5. Held-out errors: K-fold cross-validation over poses (the CSV's ``fold`` column when given): each fold refits
   the nuisance (and the named causes) on the other poses and predicts its own; marker errors in mm before and
   after, and the leave-one-group-out table (the named explanation with one cause removed).

Noise. sigma is the case's ``[measurement] sigma_m`` or ``--sigma-mm``; else the pooled scatter of repeated poses
(same joint angles); else -- stated as a warning and in ``sigma_source`` -- the K-fold held-out residual of the
most flexible rival (every cause on every eligible joint at once), its parameters counted
(:func:`heldout_sigma`): it does not depend on the explanation judged. The nuisance identifiability is then
decided again at that sigma, and the search over explanations runs once, at it.
"""
from __future__ import annotations

import dataclasses
import itertools
import logging
import math

import numpy as np
import scipy.linalg
from scipy import stats
from scipy.optimize import lsq_linear

from femcheck.diagnose import evidence
from femcheck.robot.causes import CAUSE_IDS, T_KEEP, VOCABULARY, Placement, candidate_placements, place_text
from femcheck.robot.elastic import ElasticParams, equilibrium, flat_layout, guide_overlap, guide_widths, joint_torques
from femcheck.robot.measurement_model import MeasurementModel, identifiable_columns
from femcheck.robot.positions import MarkerPositions
from femcheck.robot.tree import forward, gravity_wrenches, rotation

log = logging.getLogger(__name__)

#: |z| of a linear trend of the residual over the measurement order above which it is a finding (drift)
DRIFT_Z = 5.0
#: backlash take-up width floor, as a share of the most loaded joint's median gravity torque
BACKLASH_FLOOR = 0.02
#: Gauss-Newton iterations of the calibration (each one full forward-difference Jacobian) and its tolerance
GN_MAX_ITER, GN_RTOL = 12, 1e-6


@dataclasses.dataclass
class _Projector:
    """QR of the nuisance block on a set of readings (plus the prior rows): projects it out of a cause block."""

    rows: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    b: np.ndarray


class LinearRivals:
    """The linearized problem at the calibrated point: sigma-weighted residual ``r`` (3R,), nuisance block ``N``
    (3R, k_n) over the identifiable columns, prior rows ``P`` (k_p, k_n) and their right-hand side ``p``, the
    elastic block ``E`` (3R, n_flat)."""

    def __init__(self, r, N, P, p, E, reading_of_row):
        self.r, self.N, self.P, self.p, self.E = r, N, P, p, E
        self.reading_of_row = reading_of_row
        self._cache: dict = {}

    def projector(self, rows: np.ndarray | None) -> _Projector:
        key = None if rows is None else rows.tobytes()
        if key not in self._cache:
            idx = np.arange(self.r.size) if rows is None else rows
            A = np.vstack([self.N[idx], self.P])
            b = np.concatenate([self.r[idx], self.p])
            Q, R = np.linalg.qr(A)
            self._cache[key] = _Projector(idx, Q, R, b)
        return self._cache[key]

    def fit(self, B: np.ndarray, lb: np.ndarray, ub: np.ndarray, rows: np.ndarray | None = None):
        """Least squares over nuisance + cause parameters (bounds on the cause ones). Returns (delta (k_n,),
        theta (k,), chi2, se (k,) of theta (inf where on a bound))."""
        pr = self.projector(rows)
        Bf = np.vstack([B[pr.rows], np.zeros((self.P.shape[0], B.shape[1]))])
        rt = pr.b - pr.Q @ (pr.Q.T @ pr.b)
        k = B.shape[1]
        theta, se = np.zeros(k), np.full(k, np.inf)
        if k:
            Bt = Bf - pr.Q @ (pr.Q.T @ Bf)
            norm = np.linalg.norm(Bt, axis=0)
            ok = norm > 0
            s = np.where(ok, norm, 1.0)
            res = lsq_linear(Bt / s, rt, bounds=(lb * s, ub * s), method="bvls" if k <= 40 else "trf", lsmr_tol="auto")
            theta = res.x / s
            free = ok & (theta > lb + 1e-12 * np.abs(lb) + 1e-300) & (theta < ub)
            if free.any():
                G = (Bt / s)[:, free]
                cov = np.linalg.pinv(G.T @ G)
                se[free] = np.sqrt(np.clip(np.diag(cov), 0, None)) / s[free]
            resid = rt - Bt @ theta
        else:
            resid = rt
        delta = scipy.linalg.solve_triangular(pr.R, pr.Q.T @ (pr.b - Bf @ theta), check_finite=False)
        return delta, theta, float(resid @ resid), se

    def predict_residual(self, delta, theta, B, rows) -> np.ndarray:
        """Sigma-weighted residual (measured - model) on ``rows`` after the linear update."""
        out = self.r[rows] - self.N[rows] @ delta
        if B.shape[1]:
            out = out - B[rows] @ theta
        return out


@dataclasses.dataclass(frozen=True)
class CauseFit:
    """A cause in its chosen placement: ``placement``, fitted ``values`` (k,) with standard errors ``se``,
    ``chi2``, ``B`` (3R, k) its sigma-weighted columns, ``lb``/``ub`` its bounds, ``tried`` {placement: BIC}."""

    placement: Placement
    values: np.ndarray
    se: np.ndarray
    chi2: float
    B: np.ndarray
    lb: np.ndarray
    ub: np.ndarray
    tried: dict

    @property
    def id(self) -> str:
        return self.placement.spec.id


@dataclasses.dataclass(frozen=True)
class SerialDiagnosis:
    """Result of :func:`diagnose_tree`; ``as_json`` gives the issue-23 contract."""

    verdict: str
    weighing: object
    causes: tuple[dict, ...]
    nuisance: dict
    identifiability: dict
    residual: dict
    heldout: dict
    leave_one_out: tuple[dict, ...]
    per_pose_error_mm_before: np.ndarray
    per_pose_error_mm_after: np.ndarray
    pose_labels: tuple[str, ...]
    warnings: tuple[str, ...]
    sigma_m: float
    sigma_source: str
    skipped: tuple[str, ...]
    cause_fits: dict = dataclasses.field(default_factory=dict, repr=False)
    #: the extended model as fitted ("after"), for writing the corrected case: nuisance ``x``, elastic ``params``,
    #: sensor frame ``R``, ``t``, ``backlash_width`` (n_ind,) N m, ``predicted`` (R, 3) m, ``units`` (per named
    #: cause: id, flat kind, unit groups, values, standard errors, probability)
    fitted: dict = dataclasses.field(default_factory=dict, repr=False)

    def as_json(self) -> dict:
        w = self.weighing
        h = self.heldout
        return {"verdict": self.verdict, "causes": list(self.causes), "alternatives": w.alternatives(),
                "ambiguous": w.ambiguous, "ambiguity": w.ambiguity,
                "evidence": "BIC (Schwarz): -2 ln p(D|M) ~ chi2 + k ln N; prior: equal mass per explanation size (none, singles, pairs), shared within the size",
                "residual": self.residual,
                "heldout_mean_error_mm_before": h["mean_before"], "heldout_mean_error_mm_after": h["mean_after"],
                "heldout_median_error_mm_before": h["median_before"], "heldout_median_error_mm_after": h["median_after"],
                "heldout_max_error_mm_before": h["max_before"], "heldout_max_error_mm_after": h["max_after"],
                "heldout_folds": h["folds"], "leave_one_out": list(self.leave_one_out),
                "nuisance": self.nuisance, "identifiability": self.identifiability,
                "sigma_source": self.sigma_source, "sigma_is_estimate": self.sigma_source.startswith("estimated"),
                "not_applicable": list(self.skipped),
                "warnings": list(self.warnings)}


def _backlash_width(tree, data, opts) -> np.ndarray:
    """(n_ind,) tanh take-up torque of each joint's backlash: the case row's ``backlash_torque_Nm`` where given."""
    w = _default_backlash_width(tree, data, opts)
    return np.where(np.isfinite(tree.backlash_width), tree.backlash_width, w)


def _default_backlash_width(tree, data, opts) -> np.ndarray:
    fk = forward(tree, data.q @ tree.coupling.T)
    F, M = gravity_wrenches(tree, fk, data.payload_kg)
    tau = np.abs(joint_torques(tree, fk, M, F))
    if opts.backlash_torque_Nm is not None:
        return np.full(tree.n_joints, opts.backlash_torque_Nm)
    med = np.median(tau, axis=0)
    # a joint the weight hardly loads has no side to settle on: its take-up is as wide as BACKLASH_FLOOR of the
    # most loaded joint's torque, so that its backlash stays a smooth (and weak) function of the pose
    return np.maximum(0.05 * med, max(BACKLASH_FLOOR * float(med.max()), 1e-6))


def _replicate_sigma(data: MarkerPositions) -> tuple[float, int]:
    """Pooled per-coordinate scatter of readings of repeated poses (same joint angles, marker); (sigma, dof)."""
    key = np.round(data.q, 9)
    _, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.ravel()
    grp = inv[data.pose] * (data.marker.max() + 1) + data.marker
    _, g = np.unique(grp, return_inverse=True)
    n = np.bincount(g).astype(float)
    mean = np.stack([np.bincount(g, data.xyz[:, k]) for k in range(3)], axis=1) / n[:, None]
    ss = float(((data.xyz - mean[g]) ** 2).sum())
    dof = int(3 * (n - 1).sum())
    return (float(np.sqrt(ss / dof)), dof) if dof >= 10 else (float("nan"), 0)


def _folds(data: MarkerPositions, k: int) -> np.ndarray:
    if data.fold is not None:
        return data.fold.copy()
    rng = np.random.default_rng(0)
    f = np.empty(data.n_poses, int)
    f[rng.permutation(data.n_poses)] = np.arange(data.n_poses) % k
    return f


def _fd_step(theta: np.ndarray, j: int) -> np.ndarray:
    """Forward-difference step on cause parameter j: 1e-3 of its value (1e-9 absolute floor), zeros elsewhere."""
    h = np.zeros(len(theta))
    h[j] = max(1e-3 * abs(theta[j]), 1e-9)
    return h


def heldout_sigma(lin: LinearRivals, B: np.ndarray, lb: np.ndarray, fold_of_row: np.ndarray, k_nuisance: int,
                  sig: float) -> tuple[float, int]:
    """sigma (m) from the K-fold held-out residual of the linear model [nuisance | B] (``lin`` weighted by ``sig``),
    and the number k of parameters counted.

    A reading predicted from a fit on the other folds (n_t = n (K-1)/K readings, k parameters) has the error
    variance sigma^2 (1 + x^T (X_t^T X_t)^-1 x), whose mean over the readings is sigma^2 (1 + k / n_t); so
    E[SS_heldout] = sigma^2 (n + k K / (K - 1)), the degrees of freedom the estimate divides by."""
    ss = 0.0
    folds = np.unique(fold_of_row)
    for f in folds:
        train, test = np.flatnonzero(fold_of_row != f), np.flatnonzero(fold_of_row == f)
        d, th, _, _ = lin.fit(B, lb, np.full(len(lb), np.inf), train)
        r = lin.predict_residual(d, th, B, test)
        ss += float(r @ r)
    K, k = len(folds), k_nuisance + B.shape[1]
    return sig * math.sqrt(ss / (lin.r.size + k * K / (K - 1))), k


def calibrate(model: MeasurementModel, params: ElasticParams, sigma: float, cols: np.ndarray | None = None,
              x0: np.ndarray | None = None, progress=None, J0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Newton (Levenberg-Marquardt damped) calibration of the nuisance vector with the prior; returns
    (x, kept columns).

    ``J0`` (3R, n_nuisance), unweighted: a Jacobian near ``x0`` to start from. The Jacobian (one forward-difference
    prediction per column, the cost of the calibration) is kept over the steps while they lower the cost
    (modified Gauss-Newton: every step is checked on the exact residual) and recomputed only when a step with it
    fails; a stale Jacobian slows the convergence a little, it does not move the point it converges to by much,
    and the linear rivals refit the nuisance at the calibrated point with a fresh one anyway."""
    lay = model.layout
    x = np.zeros(lay.size) if x0 is None else x0.copy()
    lam = 1e-3
    f = model.predict(x, params).ravel()
    meas = model.data.xyz.ravel()
    kept = cols

    def cost(x, f):
        pri = x[np.isfinite(lay.prior_sigma)] / lay.prior_sigma[np.isfinite(lay.prior_sigma)]
        return float((((meas - f) / sigma) ** 2).sum() + (pri ** 2).sum())

    c = cost(x, f)
    J, fresh, evaluations = (None, False, 0) if J0 is None else (J0 / sigma, False, 0)
    for it in range(4 * GN_MAX_ITER):
        if J is None:
            J, fresh = model.jacobian(x, params, base=f) / sigma, True
            evaluations += 1
        if kept is None:
            kept, _, _ = identifiable_columns(J, lay.prior_sigma)
        Jk = J[:, kept]
        ps = lay.prior_sigma[kept]
        fin = np.isfinite(ps)
        A = np.vstack([Jk, np.diag(1.0 / np.where(fin, ps, np.inf))[fin]])
        b = np.concatenate([(meas - f) / sigma, -x[kept][fin] / ps[fin]])
        H, g = A.T @ A, A.T @ b
        lam_try = lam
        while True:
            step = np.linalg.solve(H + lam_try * np.diag(np.diag(H) + 1e-30), g)
            xn = x.copy()
            xn[kept] += step
            fn = model.predict(xn, params).ravel()
            cn = cost(xn, fn)
            if cn <= c or lam_try > 1e8 or (not fresh and lam_try > 1e-1):
                break
            lam_try *= 10
        if progress:
            progress(f"calibration pass {it + 1}: chi2 {cn:.4g}")
        if cn > c and not fresh:
            J = None              # the kept Jacobian no longer gives a descent step: recompute it here
            continue
        done = cn <= c and (c - cn) <= GN_RTOL * max(c, 1.0)
        if cn <= c:
            x, f, c, lam = xn, fn, cn, max(lam_try / 10, 1e-9)
            fresh = False
        else:
            lam = lam_try
        if done or lam > 1e8 or evaluations >= GN_MAX_ITER:
            break
    return x, kept


def diagnose_tree(case, data: MarkerPositions, sigma_m: float | None = None, folds: int | None = None,
                  pairs: bool = True, progress=None) -> SerialDiagnosis:
    """Diagnose ``data`` against the ``serial_tree`` ``case`` (module docstring)."""
    say = progress or (lambda s: None)
    tree, opts = case.tree, case.diagnosis
    warnings: list[str] = []
    if data.fold is not None and len(np.unique(data.fold)) < 2:
        from femcheck.errors import MeasuredDataError
        raise MeasuredDataError(data.source, None, "fold", f"has the single value {int(data.fold[0])}; cross-validation "
                                "needs at least 2 folds (or leave the column out for K random folds)")
    if data.missing:
        warnings.append(f"{data.missing} readings with an empty or nan coordinate (occluded markers) left out")
    K = folds or case.measurement.folds
    # ---- noise -------------------------------------------------------------------------------------------
    sig_rep, rep_dof = _replicate_sigma(data)
    if sigma_m is not None:
        sigma, src = float(sigma_m), "stated (--sigma-mm)"
    elif case.measurement.sigma_m is not None:
        sigma, src = float(case.measurement.sigma_m), "stated (case measurement.sigma_m)"
    elif np.isfinite(sig_rep):
        sigma, src = sig_rep, f"repeated poses ({rep_dof} dof)"
    else:
        sigma, src = float("nan"), "estimated"
    work_sigma = sigma if np.isfinite(sigma) else 1e-4
    # ---- before: calibrate the model as given ---------------------------------------------------------------
    nominal = ElasticParams.nominal(tree)
    bw = _backlash_width(tree, data, opts)
    _fk0 = forward(tree, data.q @ tree.coupling.T)
    _F0, _M0 = gravity_wrenches(tree, _fk0, data.payload_kg)
    tau_ind = joint_torques(tree, _fk0, _M0, _F0)
    _overlap = guide_overlap(tree, data.q @ tree.coupling.T)
    for r in np.flatnonzero(np.isfinite(_overlap).any(axis=0)):
        if not np.all(_overlap[:, r] > 0):
            from femcheck.errors import MeasuredDataError
            k = int(np.argmin(_overlap[:, r]))
            from femcheck.robot.positions import q_column
            col = q_column(int(np.flatnonzero(tree.independent == r)[0]), True) if r in tree.independent else "q"
            raise MeasuredDataError(data.source, None, col, f"pose {data.pose_labels[k]} slides joint {tree.names[r]} to "
                                    f"{data.q[k] @ tree.coupling[r]:.4g} m, beyond its guide overlap "
                                    f"guide_overlap_m = {tree.guide_overlap[r]:.4g} m (L(q) = L0 - q must stay > 0)")
    mm = MeasurementModel(tree, data, opts, opts.fixed_point_passes, bw, guide_widths(tree, _fk0, _M0))
    mm.align(nominal)
    say("calibrating the model as given (sensor frame, marker offsets, geometry)")
    lay = mm.layout
    # which geometry the data identify is decided on the rigid model: a direction only the elastic response
    # could see (the robot's tilt against gravity, say) would otherwise be calibrated into the effects diagnosed
    rigid = ElasticParams.rigid(tree)
    J_start = mm.jacobian(np.zeros(lay.size), rigid)
    kept0, _, _ = identifiable_columns(J_start / work_sigma, lay.prior_sigma)
    x_b, _ = calibrate(mm, nominal, work_sigma, cols=kept0, progress=say, J0=J_start)
    f_b = mm.predict(x_b, nominal).ravel()
    Jn = mm.jacobian(x_b, nominal, base=f_b)
    J_rigid = Jn if nominal.is_rigid else mm.jacobian(x_b, rigid)

    def identify(sig, kept_before):
        """The identifiable nuisance set decided at ``sig`` on the rigid Jacobian at the calibrated point; when it
        differs from ``kept_before``, those columns are calibrated too (and the point's Jacobians redone)."""
        nonlocal x_b, f_b, Jn, J_rigid
        kept, fixed, cond = identifiable_columns(J_rigid / sig, lay.prior_sigma)
        if set(kept) != set(kept_before):
            x_b, _ = calibrate(mm, nominal, sig, cols=kept, x0=x_b, progress=say, J0=Jn)
            f_b = mm.predict(x_b, nominal).ravel()
            Jn = mm.jacobian(x_b, nominal, base=f_b)
            J_rigid = Jn if nominal.is_rigid else mm.jacobian(x_b, rigid)
            return kept, fixed, cond, True
        return kept, fixed, cond, False

    kept, fixed, cond, _ = identify(work_sigma, kept0)
    say("linearizing the elastic causes")
    E = mm.elastic_jacobian(x_b, nominal, base=f_b)
    reading_of_row = np.repeat(np.arange(data.n_readings), 3)

    def build(sig):
        ps = lay.prior_sigma[kept]
        fin = np.isfinite(ps)
        P = np.diag(1.0 / np.where(fin, ps, np.inf))[fin]
        p = -x_b[kept][fin] / ps[fin]
        return LinearRivals((data.xyz.ravel() - f_b) / sig, Jn[:, kept] / sig, P, p, E / sig, reading_of_row)

    lin = build(work_sigma)
    # ---- the vocabulary: each cause in its best placement ------------------------------------------------
    lay_f = flat_layout(tree)
    n_data = 3 * data.n_readings
    nom_flat = nominal.flat()

    def columns(pl: Placement, lin):
        sl = lay_f[pl.spec.flat]
        sub = lin.E[:, sl]
        B = np.column_stack([sub[:, list(g)].sum(axis=1) for g in pl.groups]) if pl.groups else np.zeros((n_data, 0))
        nom = nom_flat[sl]
        if pl.spec.lower == "nominal":
            lb = np.array([-min(nom[list(g)]) for g in pl.groups])
        else:
            lb = np.full(len(pl.groups), float(pl.spec.lower))
        return B, lb, np.full(len(pl.groups), np.inf)

    def fit_placement(pl: Placement, lin, rows=None, extra=None):
        """Fit one placement (with ``extra`` = (B, lb, ub) of other causes fitted jointly); the per-joint placement
        is pruned by backward elimination over its own parameters."""
        B, lb, ub = columns(pl, lin)
        Be, lbe, ube = extra if extra is not None else (np.zeros((n_data, 0)), np.zeros(0), np.zeros(0))
        delta, th, chi2, se = lin.fit(np.hstack([B, Be]), np.concatenate([lb, lbe]), np.concatenate([ub, ube]), rows)
        if pl.kind in ("joint", "size", "branch"):   # backward elimination: keep the places the data see
            while pl.n_params:
                k = pl.n_params
                t = np.where(np.isfinite(se[:k]) & (se[:k] > 0), np.abs(th[:k]) / np.where(se[:k] > 0, se[:k], 1), 0.0)
                t[th[:k] <= lb + 1e-300] = 0.0
                j = int(np.argmin(t))
                if t[j] >= T_KEEP:
                    break
                keep = [i for i in range(k) if i != j]
                pl = pl.restricted(keep)
                B, lb, ub = B[:, keep], lb[keep], ub[keep]
                delta, th, chi2, se = lin.fit(np.hstack([B, Be]), np.concatenate([lb, lbe]), np.concatenate([ub, ube]), rows)
        k = pl.n_params
        return pl, B, lb, ub, th[:k], se[:k], chi2

    spec_of = {s.id: s for s in VOCABULARY}

    def eligibility(lin) -> tuple[dict[str, np.ndarray], list[str]]:
        """{cause id: eligible units} (units whose column the nuisance block does not absorb) and the reasons of
        the causes left out."""
        skipped, eligible_of = [], {}
        pr0 = lin.projector(None)
        for spec in VOCABULARY:
            sub = lin.E[:, lay_f[spec.flat]]
            full = np.linalg.norm(sub, axis=0)
            padded = np.vstack([sub, np.zeros((lin.P.shape[0], sub.shape[1]))])
            proj = np.linalg.norm(padded - pr0.Q @ (pr0.Q.T @ padded), axis=0)
            ok = (full > 0) & (proj > 1e-3 * np.where(full > 0, full, 1)) & (proj > 1e-6)
            rows_ok = spec.applies(tree)
            if spec.unit == "joint":
                ok &= rows_ok[tree.independent]
            elif spec.unit in ("row", "link"):
                ok &= rows_ok
            if spec.id == "gear_clearance":   # only joints the weight loads to one side over a useful range
                ok &= np.median(np.abs(tau_ind), axis=0) > 2 * BACKLASH_FLOOR * np.median(np.abs(tau_ind), axis=0).max()
            eligible = np.flatnonzero(ok)
            if not rows_ok.any():
                skipped.append(f"{spec.id}: the robot has no "
                               f"{'prismatic joint with a stated guide_overlap_m' if spec.rows == 'guided' else spec.rows + ' joint'}")
                continue
            if not len(eligible):
                skipped.append(f"{spec.id}: no effect on the readings" +
                               (" (the model has no elastic element for the masses to load)" if spec.id == "mass_scale" else
                                " that the nuisance parameters cannot absorb"))
                continue
            eligible_of[spec.id] = eligible
        return eligible_of, skipped

    fold = _folds(data, K)
    fold_of_row = np.repeat(fold[data.pose], 3)
    eligible_of, skipped = eligibility(lin)
    if not np.isfinite(sigma):
        # sigma from what does not depend on the explanation judged: the held-out residual of the most flexible
        # rival (every cause on every eligible unit at once); then identifiability is decided again at that sigma
        say("estimating sigma from the held-out residual of the most flexible rival")
        units = sorted({lay_f[spec_of[c].flat].start + int(u) for c, us in eligible_of.items() for u in us})
        B = lin.E[:, units]
        lower = {lay_f[sp.flat].start + int(u): sp.lower for sp in VOCABULARY if sp.id in eligible_of
                 for u in eligible_of[sp.id]}
        lb = np.array([-nom_flat[i] if lower[i] == "nominal" else float(lower[i]) for i in units])
        sigma, k_flex = heldout_sigma(lin, B, lb, fold_of_row, len(kept), work_sigma)
        src = (f"estimated: {len(np.unique(fold))}-fold held-out residual of the most flexible rival (every cause on "
               f"every eligible joint, {k_flex} parameters with the nuisance, counted)")
        warnings.append(f"sigma not stated and no repeated poses: sigma = {sigma * 1e3:.3f} mm from the held-out residual "
                        f"of the most flexible rival; state [measurement] sigma_m (or --sigma-mm) for a verdict that "
                        "can tell an effect outside the vocabulary")
        kept, fixed, cond, moved = identify(sigma, kept)
        if moved:
            E = mm.elastic_jacobian(x_b, nominal, base=f_b)
        lin = build(sigma)
        eligible_of, skipped = eligibility(lin)
    lin_sigma = [sigma]

    def penalty(pl: Placement) -> float:
        """Extended-BIC term 2 ln C(p, k) of a per-joint placement that picked k of its p eligible units (the
        search over places is itself a choice among models; without it, extra places win by chance)."""
        if pl.kind != "joint":
            return 0.0
        p, k = len(eligible_of[pl.spec.id]), pl.n_params
        return 2.0 * (math.lgamma(p + 1) - math.lgamma(k + 1) - math.lgamma(p - k + 1))

    def search(cid, lin, extra=None) -> CauseFit | None:
        """The cause in its placement of smallest BIC (given ``extra`` causes fitted with it)."""
        tried, best = {}, None
        ke = 0 if extra is None else extra[0].shape[1]
        for pl in candidate_placements(spec_of[cid], tree, eligible_of[cid]):
            pl2, B, lb, ub, th, se, chi2 = fit_placement(pl, lin, extra=extra)
            if not pl2.n_params:
                continue
            b = evidence.bic(chi2, pl2.n_params + ke, n_data) + penalty(pl2)
            tried[pl.kind] = b
            if best is None or b < best[0]:
                best = (b, CauseFit(pl2, th, se, chi2, B, lb, ub, tried))
        return None if best is None else best[1]

    def fit_combo(ids, lin, rows=None):
        pls = placed[tuple(ids)]
        if not pls:
            return lin.fit(np.zeros((n_data, 0)), np.zeros(0), np.zeros(0), rows), []
        cols = [columns(pl, lin) for pl in pls]
        B = np.hstack([c[0] for c in cols])
        lb, ub = np.concatenate([c[1] for c in cols]), np.concatenate([c[2] for c in cols])
        return lin.fit(B, lb, ub, rows), cols

    def build_rivals(lin):
        """none, every cause in its best placement, every pair with placements chosen jointly (two alternating
        rounds: each cause's placement re-chosen with the other fitted beside it)."""
        singles = {cid: f for cid in eligible_of if (f := search(cid, lin)) is not None}
        placed.clear()
        placed[()] = ()
        for cid, f in singles.items():
            placed[(cid,)] = (f.placement,)
        if pairs:
            for a, b in itertools.combinations(singles, 2):
                pa, pb = singles[a].placement, singles[b].placement
                for _ in range(2):
                    fa = search(a, lin, columns(pb, lin))
                    pa = fa.placement if fa is not None else pa
                    fb = search(b, lin, columns(pa, lin))
                    pb = fb.placement if fb is not None else pb
                placed[(a, b)] = (pa, pb)
        out = []
        for ids, pls in placed.items():
            (delta, th, chi2, se), _ = fit_combo(ids, lin)
            out.append(evidence.Explanation(tuple(ids), chi2, sum(pl.n_params for pl in pls), (th, se),
                                            penalty=sum(penalty(pl) for pl in pls)))
        return out, singles

    fin_k = lambda: np.isfinite(lay.prior_sigma[kept])
    _refined: dict = {}

    def refine(ids, iterations: int = 3):
        """The explanation ``ids`` on the full nonlinear model (fixed-point passes, exact rotations): modified
        Newton from its linear solution with the linearized Jacobian and the exact residual. Returns (nuisance x,
        elastic params, cause parameters, chi^2 with the prior)."""
        key = tuple(ids)
        if key in _refined:
            return _refined[key]
        (delta, theta, _, _), cols = fit_combo(key, lin)
        pls = placed[key]
        B_all = np.hstack([c[0] for c in cols]) if cols else np.zeros((n_data, 0))
        lb_all = np.concatenate([c[1] for c in cols]) if cols else np.zeros(0)
        ub_all = np.concatenate([c[2] for c in cols]) if cols else np.zeros(0)

        def elastic(theta):
            inc = np.zeros(lay_f["mass_scale"].stop)
            k0 = 0
            for pl in pls:
                for g, v in zip(pl.groups, theta[k0:k0 + pl.n_params]):
                    inc[lay_f[pl.spec.flat].start + np.array(g)] += v
                k0 += pl.n_params
            return nominal.shifted(tree, inc)

        x = x_b.copy()
        x[kept] += delta
        params = elastic(theta)
        if log.isEnabledFor(logging.DEBUG):
            big = np.argsort(-np.abs(delta / np.where(np.isfinite(lay.prior_sigma[kept]), lay.prior_sigma[kept], 1.0)))[:4]
            log.debug("refine %s: largest nuisance steps %s; cause params %s", "+".join(key) or "none",
                      [(lay.names[kept[i]], float(delta[i])) for i in big], theta)
        meas = data.xyz.ravel()
        prior_chi2 = lambda x: float(((x[kept][fin_k()] / lay.prior_sigma[kept][fin_k()]) ** 2).sum())
        cost = lambda f, x: float((((meas - f) / lin_sigma[0]) ** 2).sum()) + prior_chi2(x)
        f = mm.predict(x, params).ravel()
        N, B, costs = lin.N, B_all, [cost(f, x)]
        for it in range(2 * iterations):
            if it == iterations:
                # still falling by more than 1 % a step: the Jacobian of the calibrated point is too far from
                # here (a cause that moves the geometry's best fit a long way); one fresh Jacobian at this point
                if costs[-2] - costs[-1] <= max(0.01 * costs[-1], 1.0):
                    break
                N = mm.jacobian(x, elastic(theta), cols=kept, base=f) / lin_sigma[0]
                B = np.column_stack([(mm.predict(x, elastic(theta + h)).ravel() - f) / (lin_sigma[0] * h[j])
                                     for j, h in ((j, _fd_step(theta, j)) for j in range(len(theta)))]) \
                    if len(theta) else B_all
            lin_k = LinearRivals((meas - f) / lin_sigma[0], N, lin.P, -x[kept][fin_k()] / lay.prior_sigma[kept][fin_k()],
                                 lin.E, reading_of_row)
            d2, t2, _, _ = lin_k.fit(B, lb_all - theta, ub_all - theta, None)
            # the first steps are taken whole (as before); the re-linearized ones are halved until they lower chi^2
            for scale in ((1.0,) if it < iterations else (1.0, 0.5, 0.25, 0.125, 0.0625)):
                x_n, theta_n = x.copy(), theta + scale * t2
                x_n[kept] += scale * d2
                f_n = mm.predict(x_n, elastic(theta_n)).ravel()
                c_n = cost(f_n, x_n)
                if c_n <= costs[-1]:
                    break
            log.debug("refine %s: step %d, chi2 %.2f -> %.2f", "+".join(key) or "none", it + 1, costs[-1], c_n)
            if c_n > costs[-1] and it >= iterations:
                break
            x, theta, f = x_n, theta_n, f_n
            costs.append(c_n)
        params = elastic(theta)
        chi2 = costs[-1]
        _refined[key] = (x, params, theta, chi2)
        return _refined[key]

    placed: dict[tuple, tuple] = {}
    say("fitting each cause in each placement; weighing none, singles and pairs")
    rv, singles = build_rivals(lin)
    # every rival's chi^2 on the full nonlinear model (its linearization around the calibrated point can be off
    # by more than the noise when the causes move the geometry's best fit)
    say("refitting every rival on the nonlinear model")
    for e in rv:
        log.debug("%s: linearized chi2 %.2f, nonlinear %.2f", e.name, e.chi2, refine(e.ids)[3])
    rv = [dataclasses.replace(e, chi2=refine(e.ids)[3]) for e in rv]
    # ---- cross-validation over poses: held-out residuals of any explanation -----------------------------------
    say(f"{K}-fold cross-validation over poses" if data.fold is None else "cross-validation over the CSV's folds")
    _held: dict = {}

    def heldout_residual(ids) -> np.ndarray:
        """(R, 3) sigma-weighted held-out residuals of the explanation ``ids`` (every fold fitted on the others)."""
        key = tuple(ids)
        if key not in _held:
            out = np.empty(n_data)
            for f in np.unique(fold):
                train = np.flatnonzero(fold_of_row != f)
                test = np.flatnonzero(fold_of_row == f)
                (d, th, _, _), cols = fit_combo(key, lin, train)
                B = np.hstack([c[0] for c in cols]) if cols else np.zeros((n_data, 0))
                out[test] = lin.predict_residual(d, th, B, test)
            _held[key] = out.reshape(-1, 3)
        return _held[key]

    hchi2 = lambda ids: float((heldout_residual(ids) ** 2).sum())
    w = evidence.weigh(rv, n_data)
    chosen = list(w.best.ids)
    # a cause is named only if it also predicts poses it was not fitted on better: the leader gives way to a nested
    # explanation (one cause fewer) whose held-out chi^2 is as low (an extra cause picked from many candidate
    # places can win the BIC by chance; on held-out poses a chance fit does not help)
    while chosen:
        subs = [tuple(c for c in chosen if c != x) for x in chosen]
        subs = [t for t in subs if t in placed]
        if not subs:
            break
        sub = min(subs, key=hchi2)
        if hchi2(sub) > hchi2(tuple(chosen)):
            break
        log.info("%s gives way to %s: held-out chi2 %.1f vs %.1f", "+".join(chosen), "+".join(sub) or "none",
                 hchi2(tuple(chosen)), hchi2(sub))
        chosen = list(sub)
    if tuple(chosen) not in placed:
        chosen = list(w.best.ids)
    chosen = list(next(k for k in placed if set(k) == set(chosen)))
    w = evidence.weigh(rv, n_data, chosen=tuple(chosen))
    # ---- after: the named explanation on the full nonlinear model ------------------------------------------
    x_a, params_a, theta, chi2_after = refine(tuple(chosen))
    f_a = mm.predict(x_a, params_a).ravel()
    chosen_pl = dict(zip(chosen, placed[tuple(chosen)]))
    (_, _, _, se), _ = fit_combo(tuple(chosen), lin)     # standard errors from the linearization (95 % = 1.96 se)
    w = evidence.weigh(rv, n_data, chosen=tuple(chosen))
    # ---- residual shape: by marker, drift over the measurement order ------------------------------------------
    res_a = (data.xyz - f_a.reshape(-1, 3))
    order = data.pose.astype(float)
    Xd = np.column_stack([np.ones_like(order), (order - order.mean()) / max(order.std(), 1e-12)])
    coef, *_ = np.linalg.lstsq(Xd, res_a / sigma, rcond=None)
    drift_z = float(np.max(np.abs(coef[1])) * np.sqrt(len(order)))
    z2 = ((res_a / sigma) ** 2).sum(axis=1)
    tot = max(float(z2.sum()), 1e-300)
    share = {tree.marker_names[k]: float(z2[data.marker == k].sum() / tot) for k in np.unique(data.marker)}
    verdict = w.verdict
    shape = []
    if abs(drift_z) > DRIFT_Z:
        shape.append("drifting_with_measurement_order")
        if verdict != "unexplained" and w.p_value < 0.05:
            verdict = "unexplained"
        warnings.append(f"the residual drifts with the measurement order (trend z = {drift_z:.1f}): no cause of the "
                        "vocabulary depends on the order")
    if verdict != w.verdict:
        w = dataclasses.replace(w, verdict=verdict)
    residual = {"chi2_per_dof": w.chi2_per_dof, "p_value": w.p_value, "sigma_m": float(sigma),
                "unexplained_fraction": w.unexplained_fraction, "chi2": float(w.best.chi2), "n_data": n_data,
                "n_params": int(w.best.n_params + len(kept)), "chi2_per_dof_none": w.chi2_per_dof_none,
                "p_value_none": w.p_value_none, "chi2_share_by_marker": share, "drift_z": drift_z,
                "rms_mm_after": float(np.sqrt(np.mean(res_a ** 2)) * 1e3),
                "rms_mm_before": float(np.sqrt(np.mean((data.xyz - f_b.reshape(-1, 3)) ** 2)) * 1e3),
                "shape": shape or (["noise"] if verdict != "unexplained" else ["unstructured"])}
    # ---- causes with probabilities, places and intervals ----------------------------------------------------
    prob = {tuple(sorted(e.ids)): p for e, p in zip(w.explanations, w.probability)}
    causes = []
    units_fitted = []
    k0 = 0
    for cid in chosen:
        f = singles[cid]
        pl = chosen_pl[cid]
        vals, ses = theta[k0:k0 + pl.n_params], se[k0:k0 + pl.n_params]
        k0 += pl.n_params
        nom = nom_flat[lay_f[pl.spec.flat]]
        params, ci = {}, {}
        for g, lab, v, s in zip(pl.groups, pl.labels, vals, ses):
            # a cause on a rigid element gives the element's value; on a modelled one, what it adds to the case's
            if pl.spec.id == "mass_scale":
                name, tot_v = "mass_scale", 1.0 + v
            elif np.any(nom[list(g)]):
                name, tot_v = f"{lab}.added_{pl.spec.param}", v
            else:
                name, tot_v = f"{lab}.{pl.spec.param}", v
            params[name] = float(tot_v)
            half = 1.96 * s if np.isfinite(s) else float("nan")
            ci[name] = [float(tot_v - half), float(tot_v + half)]
        units = [u for g in pl.groups for u in g]
        rows = (tree.independent[units] if pl.spec.unit == "joint" else np.array(units, int)) \
            if pl.spec.unit != "single" else np.array([], int)
        p_cause = min(1.0, float(sum(p for ids, p in prob.items() if cid in ids)))
        units_fitted.append((cid, pl.spec.flat, pl.groups, np.array(vals), np.array(ses), p_cause))
        causes.append({"id": cid, "probability": p_cause,
                       "params": params, "params_ci": ci, "location": place_text(pl, tree), "placement": pl.kind,
                       "joints": [tree.names[r] for r in rows], "physics": pl.spec.physics,
                       "placements_bic_alone": {k: float(v) for k, v in f.tried.items()}})
    if not causes:
        causes = [{"id": "none", "probability": float(prob.get((), 0.0)), "params": {}, "params_ci": {},
                   "location": "", "placement": "", "joints": []}]
    # ---- held-out errors and the leave-one-group-out table -------------------------------------------------
    def heldout(ids) -> np.ndarray:
        """Held-out marker errors (R,) mm of an explanation: each fold refitted on the other poses."""
        return np.linalg.norm(heldout_residual(ids), axis=1) * sigma * 1e3

    e_before = heldout(())
    e_after = heldout(tuple(chosen)) if chosen else e_before
    loo = []
    for cid in chosen:
        rest = tuple(i for i in chosen if i != cid)
        e = heldout(rest)
        loo.append({"id": cid, "heldout_mean_error_mm": float(e.mean()), "heldout_max_error_mm": float(e.max()),
                    "removed_from": "+".join(chosen)})
    count = np.bincount(data.pose, minlength=data.n_poses)
    pose_err = lambda e: np.bincount(data.pose, e, minlength=data.n_poses) / np.maximum(count, 1)
    ho = {"mean_before": float(e_before.mean()), "mean_after": float(e_after.mean()),
          "median_before": float(np.median(e_before)), "median_after": float(np.median(e_after)),
          "max_before": float(e_before.max()), "max_after": float(e_after.max()), "folds": int(len(np.unique(fold)))}
    # ---- nuisance report ------------------------------------------------------------------------------------
    nuis = _nuisance_json(mm, x_a, kept, fixed, lin, sigma)
    ident = {"rank": int(len(kept)), "n_params": int(lay.size), "condition_number": cond,
             "fixed": [lay.names[i] for i in fixed],
             "prior": {"length_m": opts.prior_length_m, "angle_deg": opts.prior_angle_deg, "marker_m": opts.prior_marker_m,
                       "frame": "none (flat)"},
             "note": "columns sigma-weighted and scaled by their prior sigma (1 m or 1 rad without one); directions whose "
                     "pivot in a column-pivoted QR falls below 1e-7 of the largest, or below 1 (the data pin them down "
                     "less well than the prior), are fixed at nominal"}
    return SerialDiagnosis(verdict=w.verdict, weighing=w, causes=tuple(causes), nuisance=nuis, identifiability=ident,
                           residual=residual, heldout=ho, leave_one_out=tuple(loo),
                           per_pose_error_mm_before=pose_err(e_before), per_pose_error_mm_after=pose_err(e_after),
                           pose_labels=data.pose_labels, warnings=tuple(warnings), sigma_m=float(sigma),
                           sigma_source=src, skipped=tuple(skipped), cause_fits=singles,
                           fitted={"x": x_a, "params": params_a, "R": rotation(x_a[:3]) @ mm.R0, "t": mm.t0 + x_a[3:6],
                                   "backlash_width": bw, "predicted": f_a.reshape(-1, 3), "units": units_fitted,
                                   "kept": kept, "nuisance_se": _nuisance_se(mm, kept, lin)})


def _nuisance_se(mm: MeasurementModel, kept, lin) -> np.ndarray:
    """(n_nuisance,) standard errors of the nuisance parameters (0 where fixed at nominal)."""
    lay = mm.layout
    pr = lin.projector(None)
    cov = np.zeros((lay.size, lay.size))
    Rinv = scipy.linalg.solve_triangular(pr.R, np.eye(pr.R.shape[0]))
    cov[np.ix_(kept, kept)] = Rinv @ Rinv.T
    return np.sqrt(np.clip(np.diag(cov), 0, None))


def _nuisance_json(mm: MeasurementModel, x, kept, fixed, lin, sigma) -> dict:
    lay = mm.layout
    se = _nuisance_se(mm, kept, lin)
    ci = lambda i: [float(x[i] - 1.96 * se[i]), float(x[i] + 1.96 * se[i])] if i in set(kept) else [float(x[i]), float(x[i])]
    fixed_set = set(int(i) for i in fixed)
    R = (rotation(x[:3]) @ mm.R0)
    t = mm.t0 + x[3:6]
    frame = {"rotation_matrix": R.tolist(), "translation_m": t.tolist(),
             "correction": {lay.names[i].split(".", 1)[1]: {"value": float(x[i]), "ci": ci(i)} for i in range(6)},
             "note": "sensor <- base: x_sensor = R p_base + t; the corrections are about the closed-form (Kabsch) alignment"}
    markers, geometry = {}, {}
    for i, name in enumerate(lay.names):
        if i < 6:
            continue
        grp, rest = name.split(".", 1)
        entry = {"value": float(x[i]), "ci": ci(i), "fixed": i in fixed_set}
        if grp == "marker":
            mk, comp = rest.split(".")
            markers.setdefault(mk, {})[f"d{comp}"] = entry
        else:
            row, comp = rest.rsplit(".", 1)
            geometry.setdefault(row, {})[("d" if grp == "geometry" else "static_d") + comp] = entry
    return {"frame": frame, "marker_offsets": markers, "geometry": geometry}
