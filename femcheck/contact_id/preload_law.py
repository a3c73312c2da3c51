"""Preload dependence of an identified contact stiffness: the power law k = c P^m, fitted in log space.

Physics. A rough joint stiffens as it is pressed together because the real contact area grows
(seed 004 §2/§4: "contact stiffness is enhanced when the load increases", Fig. 4(e); §4.2 identifies
k_n at several preloads). A power law is the usual summary: Hertz contact of a single asperity gives
m = 1/3, statistical rough-surface models (Greenwood–Williamson) give m close to 1, and measured
flat joints lie in between. femcheck fits

    ln k_j = ln c + m ln P_j + e_j,       j = 1..n, P in N, k in N/m, c in N/m / N^m,

by weighted linear least squares with weights w_j = 1 / sigma_j^2 (sigma_j = 1-sigma of ln k_j,
e.g. from the frequency identification). The parameter covariance is

    Cov(ln c, m) = s^2 (X^T W X)^-1,  X = [1, ln P],

with s^2 = chi^2 / (n - 2) (the scatter of the data; ``absolute_sigma=False``, the default) or s^2 = 1
(``absolute_sigma=True``: trust the given sigma_j). The confidence band of the fitted law at P is
ln k(P) +- t_{n-2} sqrt(x^T Cov x), x = (1, ln P); the prediction band for a new measurement adds the
residual variance s^2 sigma_ref^2 (sigma_ref = rms of the given sigma_j) under the square root.
"""
from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np
from scipy import stats

from femcheck.contact_id.bar_on_spring import ContactIdError

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class PowerLaw:
    """Fitted k = c P^m. ``ln_c``, ``m``; ``cov`` (2, 2) covariance of (ln c, m); ``dof`` = n - 2;
    ``residual_var`` = s^2 (variance factor of ln k residuals, see module docstring); ``sigma_ref``
    rms of the given ln k sigmas (1 when none were given); ``preloads_N``, ``k_N_m`` the data."""

    ln_c: float
    m: float
    cov: np.ndarray
    dof: int
    residual_var: float
    sigma_ref: float
    preloads_N: np.ndarray
    k_N_m: np.ndarray

    @property
    def c(self) -> float:
        """c in N/m per N^m."""
        return math.exp(self.ln_c)

    @property
    def sigma_m(self) -> float:
        return float(math.sqrt(self.cov[1, 1])) if np.all(np.isfinite(self.cov)) else float("nan")

    @property
    def sigma_ln_c(self) -> float:
        return float(math.sqrt(self.cov[0, 0])) if np.all(np.isfinite(self.cov)) else float("nan")

    def __call__(self, preload_N) -> np.ndarray:
        """k(P) = c P^m, N/m, for preload(s) in N."""
        return np.exp(self.ln_c + self.m * np.log(np.asarray(preload_N, dtype=float)))

    def band(self, preload_N, level: float = 0.95, prediction: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) k in N/m of the two-sided ``level`` confidence band of the law (or the
        prediction band of a new measurement when ``prediction``). NaN when dof = 0."""
        lnP = np.log(np.asarray(preload_N, dtype=float))
        X = np.stack([np.ones_like(lnP), lnP], axis=-1)
        var = np.einsum("...i,ij,...j->...", X, self.cov, X)
        if prediction:
            var = var + self.residual_var * self.sigma_ref**2
        if self.dof < 1:
            nan = np.full_like(lnP, np.nan)
            return nan, nan
        t = stats.t.ppf(0.5 + 0.5 * level, self.dof)
        mid = self.ln_c + self.m * lnP
        half = t * np.sqrt(var)
        return np.exp(mid - half), np.exp(mid + half)

    def as_json(self) -> dict:
        return {"law": "k = c * P^m", "c_N_per_m_per_N^m": self.c, "m": self.m, "sigma_ln_c": self.sigma_ln_c,
                "sigma_m": self.sigma_m, "cov_lnc_m": self.cov.tolist(), "dof": self.dof,
                "residual_var": self.residual_var}


def fit_power_law(preloads_N, k_N_m, sigma_ln_k=None, *, absolute_sigma: bool = False) -> PowerLaw:
    """Fit k = c P^m to stiffnesses ``k_N_m`` (n,) N/m identified at preloads ``preloads_N`` (n,) N.

    ``sigma_ln_k`` (n,) optional 1-sigma of ln k per point (weights). Needs n >= 2 distinct preloads;
    with n = 2 the law is exact and its uncertainty unknown (NaN covariance).
    """
    P = np.atleast_1d(np.asarray(preloads_N, dtype=float))
    k = np.atleast_1d(np.asarray(k_N_m, dtype=float))
    if P.shape != k.shape or P.ndim != 1:
        raise ContactIdError(f"{P.size} preloads but {k.size} stiffnesses; expected one preload per identified stiffness")
    for name, v in (("preload", P), ("stiffness", k)):
        bad = ~(np.isfinite(v) & (v > 0))
        if np.any(bad):
            raise ContactIdError(f"{name} = {v[bad][0]!r}; expected a finite value > 0 for the power law fit")
    if np.unique(P).size < 2:
        raise ContactIdError(f"preloads = {P.tolist()}; expected at least 2 distinct preloads to fit k = c P^m")
    sig = np.ones_like(k) if sigma_ln_k is None else np.broadcast_to(np.asarray(sigma_ln_k, dtype=float), k.shape)
    if np.any(~(np.isfinite(sig) & (sig > 0))):
        raise ContactIdError(f"sigma_ln_k = {np.asarray(sigma_ln_k).tolist()}; expected finite values > 0")
    w = 1.0 / sig**2
    X = np.stack([np.ones_like(P), np.log(P)], axis=1)
    y = np.log(k)
    A = X.T @ (w[:, None] * X)
    beta = np.linalg.solve(A, X.T @ (w * y))
    r = y - X @ beta
    dof = P.size - 2
    chi2 = float(np.sum(w * r**2))
    if absolute_sigma:
        s2 = 1.0
    else:
        s2 = chi2 / dof if dof > 0 else float("nan")
    cov = s2 * np.linalg.inv(A)
    sigma_ref = float(np.sqrt(np.mean(sig**2))) if sigma_ln_k is not None else 1.0
    log.debug("power law fit: ln c=%g m=%g chi2=%g dof=%d", beta[0], beta[1], chi2, dof)
    return PowerLaw(ln_c=float(beta[0]), m=float(beta[1]), cov=cov, dof=dof, residual_var=float(s2),
                    sigma_ref=sigma_ref, preloads_N=P, k_N_m=k)
