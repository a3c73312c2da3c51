"""Structured lack of fit: does the residual of an explanation still hold a linear-elastic discrepancy that
noise cannot make?

Two discrepancy spaces are tested (Bonferroni: the smaller p-value times 2 is the test's p-value):

* ``case``: one free compliance per (point, direction) and axis (below), any pattern over the poses;
* ``smooth``: per load direction and axis, a compliance that varies smoothly over the workspace,
  c(xi) = c0 + c . xi + c2 |xi|^2 (xi the TCP position, centred and scaled over the measured poses): 5 columns
  per direction and axis instead of one per pose. A misfit of a physical element that the vocabulary lacks (a
  compliant base, a shear of the dial stand) varies smoothly with the pose, and the fewer columns see it through
  less noise (the Kennedy-O'Hagan discrepancy with a smooth, low-order kernel).

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
    kind: str = "case"

    def as_dict(self) -> dict:
        return {"lack_of_fit_chi2": self.chi2, "lack_of_fit_dof": self.dof, "lack_of_fit_columns": self.n_columns,
                "lack_of_fit_chi2_per_dof": self.chi2_per_dof, "lack_of_fit_p_value": self.p_value,
                "lack_of_fit_pure_error_ratio": self.pure_error_ratio, "lack_of_fit_pure_error_dof": self.pure_error_dof,
                "lack_of_fit_space": self.kind}


def discrepancy_basis(readings, kind: str = "case") -> np.ndarray:
    """(m, 3, n) raw discrepancy columns: entry (s, a, j) is the reading on axis a of state s per unit of
    column j's coefficient. ``case``: |F_s| on the columns (group of s, a); ``smooth``: |F_s| phi_k(xi_s) on the
    columns (direction of s, a, k), phi = (1, xi_x, xi_y, xi_z, |xi|^2)."""
    f = np.linalg.norm(readings.force, axis=1)
    m = len(f)
    if kind == "case":
        keys = list(zip(np.asarray(readings.point).tolist(), np.asarray(readings.direction).tolist()))
        index = {k: i for i, k in enumerate(dict.fromkeys(keys))}
        group = np.array([index[k] for k in keys], int)
        phi = np.ones((m, 1))
    elif kind == "smooth":
        dirs = np.asarray(readings.direction).tolist()
        index = {k: i for i, k in enumerate(dict.fromkeys(dirs))}
        group = np.array([index[k] for k in dirs], int)
        xyz = np.asarray(readings.pose, float)[:, :3]
        xi = (xyz - xyz.mean(0)) / max(float(np.abs(xyz - xyz.mean(0)).max()), 1e-12)
        phi = np.column_stack([np.ones(m), xi, np.sum(xi ** 2, axis=1)])
    else:
        raise ValueError(f"unknown discrepancy basis {kind!r}; expected case or smooth")
    n_g, n_k = int(group.max()) + 1 if m else 0, phi.shape[1]
    B = np.zeros((m, 3, n_g * 3 * n_k))
    for a in range(3):
        cols = (group * 3 + a) * n_k
        for k in range(n_k):
            B[np.arange(m), a, cols + k] = f * phi[:, k]
    return B


def structured_lack_of_fit(readings, predicted: np.ndarray, *, jacobian: np.ndarray | None = None,
                           n_params: int = 0, sigma_dof: int = 0, kind: str = "case") -> LackOfFit:
    """The test of the module docstring in the discrepancy space ``kind`` for an explanation predicting
    ``predicted`` (m, 3) m readings.

    ``jacobian``: (3 m, k) Jacobian of the weighted residual vector (row order state-major, axes x, y, z) of the
    explanation's fit, any parametrization; without it the fit is taken to absorb ``n_params`` whole columns
    (dof = m_S - k, the conservative end)."""
    if kind == "both":
        a = structured_lack_of_fit(readings, predicted, jacobian=jacobian, n_params=n_params, sigma_dof=sigma_dof)
        b = structured_lack_of_fit(readings, predicted, jacobian=jacobian, n_params=n_params, sigma_dof=sigma_dof,
                                   kind="smooth")
        lead = a if a.p_value <= b.p_value else b
        return dataclasses.replace(lead, p_value=min(1.0, 2.0 * lead.p_value), kind=f"{lead.kind} (of case, smooth)")
    m = len(readings.phase)
    Bw = (discrepancy_basis(readings, kind) / readings.sigma[:, :, None]).reshape(3 * m, -1)
    Bw = Bw[:, np.any(Bw != 0, axis=0)]
    r = ((predicted - readings.disp) / readings.sigma).ravel()
    if Bw.shape[1] == 0:
        return LackOfFit(0.0, 1.0, 0, 0.0, 1.0, kind=kind)
    Q, R = np.linalg.qr(Bw)
    d = np.abs(np.diag(R))
    Q = Q[:, d > 1e-10 * d.max()]
    m_s = Q.shape[1]
    T = float(np.sum((Q.T @ r) ** 2))
    absorbed = float(n_params)
    if jacobian is not None and jacobian.size and jacobian.shape[0] == r.size:
        QJ = Q.T @ jacobian                                  # tr(P_S H) = tr((J^T J)^+ J^T Q Q^T J)
        absorbed = float(np.trace(np.linalg.pinv(jacobian.T @ jacobian) @ (QJ.T @ QJ)))
    dof = max(m_s - absorbed, 1.0)
    kappa, nu = pure_error_ratio(readings, Q)
    if nu > 0:
        p = float(stats.f.sf(T / dof / kappa, dof, nu))
    elif sigma_dof > 0:
        p = float(stats.f.sf(T / dof, dof, int(sigma_dof)))
    else:
        p = float(stats.chi2.sf(T, dof))
    return LackOfFit(T, dof, m_s, T / dof / kappa, p, kappa, nu, kind)


def pure_error_ratio(readings, Q: np.ndarray) -> tuple[float, int]:
    """(kappa, nu_S): the trial scatter of the per-trial projections on the orthonormal discrepancy columns ``Q``
    (3 m, m_S) of the weighted space over what the pooled reading sigma predicts (module docstring), and its degrees
    of freedom; (1.0, 0) without raw readings, replicates, or when the states do not all share the same trials."""
    if readings.row_state is None or readings.row_disp is None:
        return 1.0, 0
    st, tr = np.asarray(readings.row_state), np.asarray(readings.row_trial)
    trials = np.unique(tr)
    n_t = len(trials)
    m = len(readings.phase)
    if n_t < 2 or len(st) != m * n_t or np.any(np.bincount(st, minlength=m) != n_t):
        return 1.0, 0
    ti = np.searchsorted(trials, tr)
    n_s = np.asarray(readings.n_trials, float)
    # the mean-reading residual's projection Q^T (mean / sigma) is the sum over trials of these per-trial terms
    x = readings.row_disp / (readings.sigma[st] * n_s[st, None])
    contrib = np.einsum("ra,rak->rk", x, Q.reshape(m, 3, -1)[st])
    c = np.zeros((n_t, Q.shape[1]))
    np.add.at(c, ti, contrib)
    t = trials.astype(float)
    X = np.column_stack([np.ones(n_t), t - t.mean()]) if n_t >= 3 else np.ones((n_t, 1))
    resid = c - X @ (np.linalg.pinv(X) @ c)      # about a line over trial order (or the mean), per column
    dof_t = n_t - X.shape[1]
    if dof_t < 1:
        return 1.0, 0
    # iid model: Cov(c_t) = I / n_t (Q^T r has unit covariance); the pooled sample covariance trace over m_S
    kappa = float(n_t * np.sum(resid ** 2) / dof_t / Q.shape[1])
    return max(kappa, 1e-12), int(Q.shape[1] * dof_t)


__all__ = ["LackOfFit", "discrepancy_basis", "structured_lack_of_fit"]
