"""Seed 001's measured-data workflow for the HISS haptic master (sec. 3-5): holes -> twists -> weights -> correction.

Input, one row per loading (DATA.csv; coordinates in the case's base frame, where ``r_i = S + l1 sin phi_i1``)::

    setup,tp,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,b1x_mm,b1y_mm,b1z_mm,...,b3z_mm,a1x_mm,...,a3z_mm

``setup`` is ``D/F`` or ``F/D`` (sec. 4.2, 4.3); ``tp`` a test point of the case (TP1..TP13); the wrench is
the force/torque reading at the platform point P (N, N m, base axes); ``b*`` / ``a*`` are the three
measured hole points before / after loading (mm).

Steps:

1. Twist of the platform at P from the holes (``hole_twist.platform_twist``: circle centre and plane
   normal, Kabsch rotation R), moved from the circle centre c to P: ``d_P = c1 - c0 + (R - I)(P - c0)``.
2. Weights W1..W11 of eqs. 10-12 for each setup and for their union (the paper's three fits), from
   deterministic restarts with the exact Jacobian, the residuals weighted by the measurement noise
   (L = diag(1/sigma^2) in eq. 11), 95 % profile-likelihood intervals and the identifiability flags of
   :func:`femcheck.vjm.weight_fitting.fit_weights` (Table 2).
3. The two-level linear correction x' = a x + b (Table 3) and the error statistics RMS, Std, M, AM of the
   fitted and the corrected model (Table 4), in mm and deg.

:func:`virtual_experiment` makes such data from the case's own model (assumed layout, see
``rcube_geometry``) for given true weights: D/F loads of random direction (< 10 N, < 0.5 N m, sec. 4.2)
at all 13 TPs, F/D loads at TP1-TP10 (0.5 kg and 1 kg along the negative diagonal, 0.5 kg on a side
socket; the socket arm, 50 mm, is assumed: the paper gives none), noise added to the twist at P.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from femcheck.errors import FemcheckError
from femcheck.measured.csv_format import read_table_rows

SETUP_NAMES = ("D/F", "F/D")
WRENCH_COLUMNS = ("fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm")
HOLE_COLUMNS = tuple(f"{s}{h}{c}_mm" for s in "ba" for h in "123" for c in "xyz")
COLUMNS = ("setup", "tp") + WRENCH_COLUMNS + HOLE_COLUMNS
G = 9.81


class HissDataError(FemcheckError, ValueError):
    """DATA.csv of the HISS workflow is malformed (the message names the file, row and what was expected)."""


@dataclass(frozen=True)
class HissData:
    """``setup`` (N,) 'D/F' | 'F/D'; ``point`` (N,) index into the case's test points; ``wrench`` (N, 6) N, N m;
    ``before``, ``after`` (N, 3, 3) hole points, m."""

    setup: np.ndarray
    point: np.ndarray
    wrench: np.ndarray
    before: np.ndarray
    after: np.ndarray


def read_csv(path: str, case) -> HissData:
    names = [tp.name.upper() for tp in case.test_points]
    rows = read_table_rows(path, COLUMNS, HissDataError)
    setup, point, num = [], [], []
    for i, r in enumerate(rows, start=2):
        if r["setup"] not in SETUP_NAMES:
            raise HissDataError(f"{path}: row {i}: setup {r['setup']!r}; expected 'D/F' or 'F/D'")
        if r["tp"].upper() not in names:
            raise HissDataError(f"{path}: row {i}: tp {r['tp']!r} is not a test point of the case ({names[0]}..{names[-1]})")
        try:
            vals = [float(r[c]) for c in WRENCH_COLUMNS + HOLE_COLUMNS]
        except (TypeError, ValueError):
            raise HissDataError(f"{path}: row {i}: non-numeric or missing value") from None
        if not np.all(np.isfinite(vals)):
            raise HissDataError(f"{path}: row {i}: non-finite value")
        setup.append(r["setup"]); point.append(names.index(r["tp"].upper())); num.append(vals)
    num = np.array(num)
    holes = 1e-3 * num[:, 6:].reshape(-1, 2, 3, 3)
    before, after = holes[:, 0], holes[:, 1]
    area = np.linalg.norm(np.cross(before[:, 1] - before[:, 0], before[:, 2] - before[:, 0]), axis=1)
    if np.any(area < 1e-8):                              # 3 points closer than ~0.1 mm to a line: no circle
        raise HissDataError(f"{path}: row {int(np.argmax(area < 1e-8)) + 2}: the three holes are (nearly) collinear")
    return HissData(setup=np.array(setup), point=np.array(point), wrench=num[:, :6], before=before, after=after)


def write_csv(path: str, case, data: HissData) -> None:
    from femcheck.report.atomic import write_text_atomic
    lines = [",".join(COLUMNS)]
    for s, p, w, b, a in zip(data.setup, data.point, data.wrench, data.before, data.after):
        vals = [*w, *(1e3 * b).ravel(), *(1e3 * a).ravel()]
        lines.append(",".join([s, case.test_points[p].name] + [repr(float(v)) for v in vals]))
    write_text_atomic(path, "\n".join(lines) + "\n")


def platform_points(case) -> np.ndarray:
    """Platform point P (m, 3) m at the case's test points (eq. 1)."""
    from femcheck.vjm.rcube_geometry import forward_position
    return forward_position(case.rcube, case.test_point_angles_rad)


def measured_twists(case, data: HissData) -> np.ndarray:
    """(N, 6) twist at P (m, rad) from the hole points (step 1 of the module doc)."""
    from scipy.spatial.transform import Rotation

    from femcheck.vjm.hole_twist import circle_centre_and_normal, platform_twist
    t = platform_twist(data.before, data.after)
    c0, _ = circle_centre_and_normal(data.before)
    R = Rotation.from_rotvec(t[:, 3:]).as_matrix()
    r = platform_points(case)[data.point] - c0
    return np.column_stack([t[:, :3] + np.einsum("nij,nj->ni", R, r) - r, t[:, 3:]])


def model_for(case, point, wrench, reading: str | None = None):
    """The :class:`RCubeWeightModel` of the case's layout at the measurements' test points; ``reading`` of eq. 10
    (default the case's ``[fitting] stiffness_scaling``)."""
    from femcheck.vjm.rcube_geometry import leg_jacobians, leg_poses
    from femcheck.vjm.rcube_weight_model import RCubeWeightModel
    Jt, Jp = leg_jacobians(leg_poses(case.rcube, platform_points(case)))
    return RCubeWeightModel(Jt, Jp, case.K_theta, case.fitting.weight_map, point, wrench,
                           case.fitting.stiffness_scaling if reading is None else reading)


def _df_loads(rng, n):
    """D/F readings (sec. 4.2): random directions, forces 2-10 N and moments 0.1-0.5 N m."""
    f = rng.normal(size=(n, 3)); m = rng.normal(size=(n, 3))
    f *= (rng.uniform(2.0, 10.0, n) / np.linalg.norm(f, axis=1))[:, None]
    m *= (rng.uniform(0.1, 0.5, n) / np.linalg.norm(m, axis=1))[:, None]
    return np.column_stack([f, m])


def _fd_loads(arm_m=0.05):
    """F/D loads (sec. 4.3): 0.5 kg, 1 kg on the middle socket, 0.5 kg on a side socket, along -diagonal."""
    u = -np.ones(3) / np.sqrt(3.0)
    side = np.array([1.0, -1.0, 0.0]) / np.sqrt(2.0) * arm_m            # assumed socket arm, normal to the diagonal
    F1, F2, F3 = 0.5 * G * u, 1.0 * G * u, 0.5 * G * u
    return np.array([[*F1, 0, 0, 0], [*F2, 0, 0, 0], [*F3, *np.cross(side, F3)]])


def virtual_experiment(case, weights, setups=SETUP_NAMES, df_per_point: int = 5, noise_mm: float = 0.02,
                       noise_deg: float = 0.02, seed: int = 0, hole_radius_m: float = 0.03) -> HissData:
    """Rows of a virtual experiment on the case's model with the given true weights (module doc)."""
    rng = np.random.default_rng(seed)
    setup, point, wrench = [], [], []
    n_tp = len(case.test_points)
    if "D/F" in setups:
        idx = np.repeat(np.arange(n_tp), df_per_point)
        setup += ["D/F"] * len(idx); point += list(idx); wrench += list(_df_loads(rng, len(idx)))
    if "F/D" in setups:
        fd = _fd_loads()
        for p in range(min(10, n_tp)):
            setup += ["F/D"] * 3; point += [p] * 3; wrench += list(fd)
    point, wrench = np.array(point, dtype=int), np.array(wrench)
    t = model_for(case, point, wrench).predict(np.asarray(weights, dtype=float))
    t = t + rng.normal(size=t.shape) * np.r_[[noise_mm * 1e-3] * 3, [np.deg2rad(noise_deg)] * 3]
    from scipy.spatial.transform import Rotation
    P = platform_points(case)[point]
    ang = np.deg2rad([0.0, 120.0, 250.0])
    local = hole_radius_m * np.column_stack([np.cos(ang), np.sin(ang), np.zeros(3)]) + [0.0, 0.0, -0.015]
    before = P[:, None, :] + local[None]
    R = Rotation.from_rotvec(t[:, 3:]).as_matrix()
    after = P[:, None, :] + t[:, None, :3] + np.einsum("nij,npj->npi", R, before - P[:, None, :])
    return HissData(setup=np.array(setup), point=point, wrench=wrench, before=before, after=after)


def _mmdeg(t):
    return np.column_stack([1e3 * t[:, :3], np.rad2deg(t[:, 3:])])


def fit_group(case, data: HissData, select, noise_mm: float = 0.02, noise_deg: float = 0.02,
              restarts: int | None = None, seed: int = 0) -> dict:
    """Weights (Table 2), correction (Table 3) and statistics (Table 4) for the rows ``select`` (bool (N,))."""
    from femcheck.vjm.hiss_published import COMPONENTS
    from femcheck.vjm.weight_fitting import error_statistics, fit_weights, seed_correction

    sel = np.asarray(select, dtype=bool)
    model = model_for(case, data.point[sel], data.wrench[sel])
    meas = measured_twists(case, data)[sel]
    sigma = np.r_[[noise_mm * 1e-3] * 3, [np.deg2rad(noise_deg)] * 3]
    f = case.fitting
    fit = fit_weights(model.predict, meas, model.n_weights, error_weight=1.0 / sigma ** 2,
                      restarts=f.restarts if restarts is None else restarts, top=f.top,
                      variance_threshold=f.variance_threshold, seed=seed,
                      jacobian=lambda w: model.predict_and_jacobian(w)[1], min_converged=3, profile=True)
    corr = seed_correction(_mmdeg(model.predict(fit.weights)), _mmdeg(meas))
    st_fit, st_tuned = error_statistics(corr.fitted_error), error_statistics(corr.tuned_error)
    names = [f"W{k + 1}" for k in range(model.n_weights)]
    keys = ("rms", "std", "mean", "abs_mean")
    return {
        "n": int(sel.sum()),
        "weights": fit.weights.tolist(),
        "variance": fit.variance.tolist(),
        "ci95_low": fit.ci_low.tolist(),
        "ci95_high": [None if not np.isfinite(v) else float(v) for v in fit.ci_high],
        "unidentifiable": [names[k] for k in np.flatnonzero(fit.unidentifiable)],
        "identified": [names[k] for k in np.flatnonzero(~fit.unidentifiable)],
        # hi / lo of the 95 % profile-likelihood interval (null = unbounded); above 4 the weight is flagged
        "interval_ratio": [None if not np.isfinite(h / lo) else float(h / lo) if lo > 0 else None
                           for lo, h in zip(fit.ci_low, fit.ci_high)],
        "reasons": {names[k]: list(fit.reasons[k]) for k in range(model.n_weights) if fit.reasons[k]},
        "cost": fit.cost,
        "restarts": fit.n_runs,
        "equivalent_runs": int(len(fit.converged)),
        "correction": {c: {"a": float(corr.a[j]), "b": float(corr.b[j])} for j, c in enumerate(COMPONENTS)},
        "statistics": {c: {"fitted": {k: float(st_fit[k][j]) for k in keys},
                           "fine_tuned": {k: float(st_tuned[k][j]) for k in keys}} for j, c in enumerate(COMPONENTS)},
    }


def run(case, data: HissData, noise_mm: float = 0.02, noise_deg: float = 0.02, restarts: int | None = None,
        seed: int = 0) -> dict:
    """Every setup present, and their union when both are (the paper's three columns), fitted under the case's
    reading of eq. 10 (``[fitting] stiffness_scaling``)."""
    groups = [(s, data.setup == s) for s in SETUP_NAMES if np.any(data.setup == s)]
    if len(groups) == 2:
        groups.append(("D/F + F/D", np.ones(len(data.setup), bool)))
    return {name: fit_group(case, data, sel, noise_mm, noise_deg, restarts, seed) for name, sel in groups}
