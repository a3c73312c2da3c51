"""Structured lack of fit: does the residual of an explanation still hold a linear-elastic discrepancy that
noise cannot make? (issue 15 item 1)

The overall goodness of fit (:func:`femcheck.diagnose.evidence.goodness`) spreads a systematic misfit over all N
readings: a discrepancy worth Delta chi^2 = 90 on N = 378 readings moves chi^2 / dof by 0.24, about two standard
deviations of a chi^2 / dof with an estimated sigma, and passes. But a misfit of a stiffness model is not spread
evenly: at each pose and load direction it is a *compliance column*, a displacement proportional to the load.

The test projects the weighted residual r = (d_model - d_meas) / sigma (m states x 3 axes) on the most general
linear-elastic discrepancy the protocol can show (a Kennedy-O'Hagan discrepancy in its simplest form): one free
compliance per (point, load direction) and axis,

    delta_g,a(state s) = c_g,a |F_s|,   g = (point, direction) of s, a = x, y, z,

i.e. the columns b_g,a with entries |F_s| / sigma_s,a on the states of group g, axis a (disjoint supports, so
the projection is a sum of one-column projections):

    T = sum_g,a (sum_s r_s,a |F_s| / sigma_s,a)^2 / sum_s (|F_s| / sigma_s,a)^2.

Under the explanation (its residual is noise), r = (I - H) e with H = J (J^T J)^-1 J^T the hat matrix of the
fit (J the Jacobian of the weighted residuals, k parameters), so E[T] = m_S - tr(P_S H) with m_S the number of
columns: the fit absorbs the part of its k directions that lies in the discrepancy space. T / dof_T is compared
with the pure error *in the same subspace* (the lack-of-fit F test against pure error, Draper & Smith §2.1):
per column and trial t, u_t = sum_s |F_s| x_s,a,t over the raw readings of that trial; under the iid reading
model Var(u_t) = sigma_r^2 sum_s |F_s|^2, and the trial scatter of u_t (about a straight line over trial order
with >= 3 trials, so a drift does not count as noise; about the mean with 2) measures it directly. Their pooled
ratio kappa (nu_S degrees of freedom) rescales T, and T / (dof_T kappa) is compared with F(dof_T, nu_S).
This matters: readings quantized to 10 um with 3 um noise are *not* iid with one sigma_r. An axis reading near
zero rounds to 0 nearly always, an on-axis one scatters over two quanta, so the sigma_r pooled over all
readings is too small for the loaded on-axis readings that dominate these columns (measured: kappa 1.2-1.4 on
clean quantized data, 1.0 without quantization). Without replicates (one trial) kappa = 1 and sigma_r's own test
applies (F(dof_T, sigma_dof) or chi^2_dof_T for a stated sigma). A systematic misfit lands almost
entirely in these m_S dimensions (m_S = 3 per case, N = 12-21 per case), so the test sees it through far less
noise than the overall chi^2: Delta chi^2 = 90 in dof_T = 81 is a 7-sigma excess.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from scipy import stats


@dataclasses.dataclass(frozen=True)
class LackOfFit:
    """``chi2`` (T above) of the residual in the linear-elastic discrepancy space, its ``dof`` (expected value
    under the explanation), ``n_columns`` m_S, ``pure_error_ratio`` kappa with ``pure_error_dof`` nu_S,
    ``chi2_per_dof`` = T / (dof kappa) and ``p_value`` (F or chi^2 upper tail)."""

    chi2: float
    dof: float
    n_columns: int
    chi2_per_dof: float
    p_value: float
    pure_error_ratio: float = 1.0
    pure_error_dof: int = 0

    def as_dict(self) -> dict:
        return {"lack_of_fit_chi2": self.chi2, "lack_of_fit_dof": self.dof, "lack_of_fit_columns": self.n_columns,
                "lack_of_fit_chi2_per_dof": self.chi2_per_dof, "lack_of_fit_p_value": self.p_value,
                "lack_of_fit_pure_error_ratio": self.pure_error_ratio, "lack_of_fit_pure_error_dof": self.pure_error_dof}


def discrepancy_basis(readings) -> tuple[np.ndarray, np.ndarray]:
    """(group (m,) int, column weight (m, 3)): the (point, direction) group of each state and |F_s| / sigma_s,a,
    the entries of the discrepancy columns in the weighted residual space."""
    keys = list(zip(np.asarray(readings.point).tolist(), np.asarray(readings.direction).tolist()))
    index = {k: i for i, k in enumerate(dict.fromkeys(keys))}
    group = np.array([index[k] for k in keys], int)
    w = np.linalg.norm(readings.force, axis=1)[:, None] / readings.sigma
    return group, w


def structured_lack_of_fit(readings, predicted: np.ndarray, *, jacobian: np.ndarray | None = None,
                           n_params: int = 0, sigma_dof: int = 0) -> LackOfFit:
    """The test of the module docstring for an explanation predicting ``predicted`` (m, 3) m readings.

    ``jacobian``: (3 m, k) Jacobian of the weighted residual vector (row order state-major, axes x, y, z) of the
    explanation's fit, any parametrization; without it the fit is taken to absorb ``n_params`` whole columns
    (dof = m_S - k, the conservative end)."""
    group, w = discrepancy_basis(readings)
    r = (predicted - readings.disp) / readings.sigma
    n_g = int(group.max()) + 1 if group.size else 0
    num = np.zeros((n_g, 3))
    den = np.zeros((n_g, 3))
    np.add.at(num, group, r * w)
    np.add.at(den, group, w * w)
    live = den > 0
    T = float(np.sum(num[live] ** 2 / den[live]))
    m_s = int(live.sum())
    absorbed = float(n_params)
    if jacobian is not None and jacobian.size and jacobian.shape[0] == r.size:
        # tr(P_S H) = tr((J^T J)^+ J^T P_S J); P_S J = sum over columns b b^T J / (b^T b)
        J = jacobian.reshape(len(group), 3, -1)
        bj = np.zeros((n_g, 3, J.shape[2]))
        np.add.at(bj, group, J * w[:, :, None])
        bj = bj[live] / np.sqrt(den[live])[:, None]
        JTJ = jacobian.T @ jacobian
        absorbed = float(np.trace(np.linalg.pinv(JTJ) @ (bj.T @ bj)))
    dof = max(m_s - absorbed, 1.0)
    kappa, nu = pure_error_ratio(readings, group, live)
    if nu > 0:
        p = float(stats.f.sf(T / dof / kappa, dof, nu))
    elif sigma_dof > 0:
        p = float(stats.f.sf(T / dof, dof, int(sigma_dof)))
    else:
        p = float(stats.chi2.sf(T, dof))
    return LackOfFit(T, dof, m_s, T / dof / kappa, p, kappa, nu)


def pure_error_ratio(readings, group: np.ndarray, live: np.ndarray) -> tuple[float, int]:
    """(kappa, nu_S): the trial scatter of the discrepancy columns' per-trial sums u_t over what the pooled
    reading sigma predicts for it (module docstring), pooled over the columns whose states all have the same
    trials, and its degrees of freedom; (1.0, 0) without raw readings or replicates."""
    if readings.row_state is None or readings.row_disp is None:
        return 1.0, 0
    st, tr = np.asarray(readings.row_state), np.asarray(readings.row_trial)
    trials = np.unique(tr)
    n_t = len(trials)
    if n_t < 2:
        return 1.0, 0
    ti = np.searchsorted(trials, tr)
    n_g = live.shape[0]
    f = np.linalg.norm(readings.force, axis=1)
    u = np.zeros((n_g, n_t, 3))
    np.add.at(u, (group[st], ti), f[st, None] * readings.row_disp)
    # a column has replicates only when every trial holds the same states of its group
    cnt = np.zeros((n_g, n_t))
    np.add.at(cnt, (group[st], ti), f[st] ** 2)
    full = np.all(np.isclose(cnt, cnt[:, :1]), axis=1) & (cnt[:, 0] > 0)
    t = trials.astype(float)
    X = np.column_stack([np.ones(n_t), t - t.mean()]) if n_t >= 3 else np.ones((n_t, 1))
    resid = u - np.einsum("ij,gjk->gik", X @ np.linalg.pinv(X), u)      # about a line (or the mean) per column
    ss = np.sum(resid ** 2, axis=1)                                      # (n_g, 3)
    dof_col = n_t - X.shape[1]
    use = full[:, None] & live
    pred = readings.reading_sigma_m ** 2 * cnt[:, 0][:, None] * dof_col
    if not use.any() or dof_col < 1:
        return 1.0, 0
    kappa = float(ss[use].sum() / max(np.broadcast_to(pred, use.shape)[use].sum(), 1e-300))
    return max(kappa, 1e-12), int(use.sum() * dof_col)


__all__ = ["LackOfFit", "discrepancy_basis", "structured_lack_of_fit"]
