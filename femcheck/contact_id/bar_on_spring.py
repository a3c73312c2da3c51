"""Bar on a normal contact spring (seed 004 §4.1, eqs. 20–31): frequencies <-> normal contact stiffness.

Physics. A uniform elastic bar (length ``l``, section ``A``, modulus ``E``, density ``rho``) is free at
x = 0 and rests on the ground through a linear normal contact spring ``k_n`` at x = l. Its
longitudinal vibration obeys (seed 004 eq. 20)

    rho A d2u/dt2 = d/dx (E A du/dx),

with EA u'(0) = 0 (eq. 21) and EA u'(l) = -k_n u(l) (eq. 22). Separation of variables (eqs. 25–28)
gives X(x) = cos(lambda x) and the frequency equation (seed 004 eq. 29 / eq. 30)

    tan(lambda l) = k_n / (E A lambda) = beta / (lambda l),     beta = k_n / k*,  k* = E A / l,

with the natural frequencies (eq. 31) omega_i = lambda_i c, c = sqrt(E / rho) (rad/s);
femcheck works in Hz: f_i = lambda_i c / (2 pi).

Forward problem: x_i = lambda_i l is the root of g(x) = x sin x - beta cos x in the bracket
((i-1) pi, (i-1) pi + pi/2) (g changes sign there for every beta > 0), found by vectorized
bisection polished with Newton steps, for any number of modes and any array of beta.

Sensitivity (implicit differentiation of eq. 30, using beta = x tan x):

    dx/dbeta = x / (beta (1 + beta) + x^2),    S_i = d ln f_i / d ln k_n = beta / (beta (1 + beta) + x_i^2).

S -> 1/2 for mode 1 at small beta (rigid mass on a spring, f ~ sqrt(k)), S -> 0 as beta -> infinity.

Inverse problem: a measured f_i of mode i gives x_i = 2 pi f_i l / c and, from eq. 30 in closed form,
beta_i = x_i tan x_i (x_i must lie in the mode-i bracket), hence k_n = beta_i k*. With a frequency
uncertainty sigma_f (absolute + relative part) the propagated uncertainty is
sigma(ln k_n) = (sigma_f / f_i) / S_i; the mode used is the one with the smallest sigma(ln k_n),
i.e. the mode most sensitive to beta (largest S_i for a purely relative frequency error; largest
S_i f_i for a purely absolute one — seed 004 §4.2 finds f3 the most sensitive in Hz).
"""
from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from femcheck.errors import FemcheckError

log = logging.getLogger(__name__)

_BISECTIONS = 60  # bracket width pi/2 -> pi/2 / 2**60 ~ 1e-18: below double precision
_NEWTON_POLISH = 3


class ContactIdError(FemcheckError, ValueError):
    """Frequencies or parameters that cannot be inverted into a contact stiffness; names the value."""


@dataclasses.dataclass(frozen=True)
class Bar:
    """The bar of seed 004 Fig. 7. SI: ``length_m`` (l), ``area_m2`` (A), ``E_Pa``, ``density_kg_m3``."""

    length_m: float
    area_m2: float
    E_Pa: float
    density_kg_m3: float

    def __post_init__(self):
        for name in ("length_m", "area_m2", "E_Pa", "density_kg_m3"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ContactIdError(f"bar.{name} = {v!r}; expected a finite number > 0")

    @property
    def wave_speed_m_s(self) -> float:
        """c = sqrt(E / rho), m/s (seed 004 eq. 31)."""
        return math.sqrt(self.E_Pa / self.density_kg_m3)

    @property
    def structure_stiffness_N_m(self) -> float:
        """k* = E A / l, N/m (seed 004, definition before eq. 30)."""
        return self.E_Pa * self.area_m2 / self.length_m

    @property
    def mass_kg(self) -> float:
        return self.density_kg_m3 * self.area_m2 * self.length_m

    def hz_per_unit_x(self) -> float:
        """f / (lambda l) = c / (2 pi l), Hz."""
        return self.wave_speed_m_s / (2.0 * math.pi * self.length_m)


def _check_modes(modes) -> np.ndarray:
    m = np.atleast_1d(np.asarray(modes))
    if m.size == 0 or not np.issubdtype(m.dtype, np.integer) or np.any(m < 1):
        raise ContactIdError(f"modes = {np.asarray(modes).tolist()}; expected mode numbers 1, 2, ... (integers >= 1)")
    return m.astype(int)


def frequency_roots(beta, n_modes: int | None = None, modes=None) -> np.ndarray:
    """Roots x_i = lambda_i l of tan x = beta / x (seed 004 eq. 30).

    beta : scalar or (n,) stiffness ratio k_n / k* (>= 0). Give either ``n_modes`` (modes 1..n) or
    ``modes`` (1-based mode numbers). Returns (n, n_modes) (or (n_modes,) for scalar beta), -.
    beta = 0 gives the free–free bar x_i = (i-1) pi; beta = inf the fixed end x_i = (i - 1/2) pi.
    """
    if modes is None:
        if n_modes is None or int(n_modes) < 1:
            raise ContactIdError(f"n_modes = {n_modes!r}; expected an integer >= 1")
        modes = np.arange(1, int(n_modes) + 1)
    modes = _check_modes(modes)
    b = np.asarray(beta, dtype=float)
    scalar = b.ndim == 0
    b = np.atleast_1d(b)
    if np.any(~(b >= 0)):
        raise ContactIdError(f"beta = {b[~(b >= 0)][0]!r}; expected a stiffness ratio >= 0")
    B = b[:, None] * np.ones((1, modes.size))
    lo = (modes[None, :] - 1) * np.pi * np.ones_like(B)
    hi = lo + 0.5 * np.pi
    inf = np.isinf(B)
    Bf = np.where(inf, 0.0, B)

    def g(x):  # x sin x - beta cos x: sign at lo is -beta (-1)^(i-1), at hi +x (-1)^(i-1)
        return x * np.sin(x) - Bf * np.cos(x)

    s_lo = np.sign(g(lo))
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        same = np.sign(g(mid)) == s_lo
        lo = np.where(same, mid, lo)
        hi = np.where(same, hi, mid)
    x = 0.5 * (lo + hi)
    for _ in range(_NEWTON_POLISH):  # g' = sin x + x cos x + beta sin x
        dg = np.sin(x) * (1.0 + Bf) + x * np.cos(x)
        step = np.where(np.abs(dg) > 0, g(x) / np.where(dg == 0, 1.0, dg), 0.0)
        x = np.clip(x - step, (modes[None, :] - 1) * np.pi, (modes[None, :] - 0.5) * np.pi)
    x = np.where(inf, (modes[None, :] - 0.5) * np.pi, x)
    x = np.where(B == 0, (modes[None, :] - 1) * np.pi, x)
    return x[0] if scalar else x


def log_sensitivity(beta, x) -> np.ndarray:
    """S = d ln f / d ln k_n = beta / (beta (1 + beta) + x^2) (implicit derivative of eq. 30), -.

    beta and x broadcast together (x from :func:`frequency_roots`). S = 0 where beta is 0 or inf
    and x > 0; mode 1 at beta = 0 (x = 0) has the limit 1/2.
    """
    b = np.asarray(beta, dtype=float)
    x = np.asarray(x, dtype=float)
    if b.ndim == 1 and x.ndim == 2:
        b = b[:, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        s = b / (b * (1.0 + b) + x**2)
    s = np.where(np.isinf(b), 0.0, s)
    return np.where((b == 0) & (x == 0), 0.5, np.where(b == 0, 0.0, s))


def natural_frequencies_Hz(bar: Bar, k_n_N_m, n_modes: int | None = None, modes=None) -> np.ndarray:
    """f_i = lambda_i c / (2 pi) (seed 004 eqs. 30–31) for contact stiffness k_n (scalar or (n,), N/m).

    Returns (n_modes,) or (n, n_modes), Hz.
    """
    k = np.asarray(k_n_N_m, dtype=float)
    x = frequency_roots(k / bar.structure_stiffness_N_m, n_modes=n_modes, modes=modes)
    return x * bar.hz_per_unit_x()


@dataclasses.dataclass(frozen=True)
class NormalIdentification:
    """Result of the inverse 1-D problem for one measurement (one preload).

    Per measured mode (arrays (n_meas,)): ``modes`` (1-based), ``frequencies_Hz``, ``x`` = lambda l,
    ``beta``, ``k_n_N_m``, ``sensitivity`` = d ln f / d ln k_n (-), ``df_dlnk_Hz`` = S f (Hz per unit
    relative change of k_n), ``sigma_ln_k`` (propagated 1-sigma of ln k_n). ``best`` is the index of
    the mode used (smallest ``sigma_ln_k``); ``k_n_N_m_best`` and ``sigma_ln_k_best`` its values.
    """

    modes: np.ndarray
    frequencies_Hz: np.ndarray
    x: np.ndarray
    beta: np.ndarray
    k_n_N_m: np.ndarray
    sensitivity: np.ndarray
    df_dlnk_Hz: np.ndarray
    sigma_ln_k: np.ndarray
    best: int

    @property
    def consistent(self) -> bool:
        """True when every mode's ln k_n lies within 3 combined sigmas of the mode used (a mode-numbering
        or model error shows up as disagreement between modes)."""
        return modes_consistent(self.k_n_N_m, self.sigma_ln_k, self.best)

    @property
    def k_n_N_m_best(self) -> float:
        return float(self.k_n_N_m[self.best])

    @property
    def sigma_ln_k_best(self) -> float:
        return float(self.sigma_ln_k[self.best])

    def as_json(self) -> dict:
        return {
            "k_n_N_per_m": self.k_n_N_m_best,
            "sigma_ln_k": self.sigma_ln_k_best,
            "mode_used": int(self.modes[self.best]),
            "modes_consistent": self.consistent,
            "per_mode": [
                {"mode": int(m), "frequency_Hz": float(f), "lambda_l": float(x), "beta": float(b),
                 "k_n_N_per_m": float(k), "sensitivity_dlnf_dlnk": float(s), "df_dlnk_Hz": float(d),
                 "sigma_ln_k": float(sg)}
                for m, f, x, b, k, s, d, sg in zip(self.modes, self.frequencies_Hz, self.x, self.beta, self.k_n_N_m,
                                                   self.sensitivity, self.df_dlnk_Hz, self.sigma_ln_k)
            ],
        }


def modes_consistent(k, sigma_ln_k, best: int, n_sigma: float = 3.0) -> bool:
    """|ln k_i - ln k_best| <= n_sigma sqrt(sigma_i^2 + sigma_best^2) for every mode i."""
    k, s = np.asarray(k, dtype=float), np.asarray(sigma_ln_k, dtype=float)
    d = np.abs(np.log(k) - np.log(k[best]))
    lim = n_sigma * np.sqrt(s**2 + s[best] ** 2)
    return bool(np.all((d <= lim) | (np.arange(k.size) == best)))


def identify_normal_stiffness(bar: Bar, frequencies_Hz, modes=None, *, sigma_f_Hz: float = 0.0,
                              sigma_f_rel: float = 1e-3) -> NormalIdentification:
    """Measured natural frequencies -> beta -> k_n (seed 004 §4.1–4.2, eqs. 30–31 inverted).

    frequencies_Hz : (n,) measured frequencies, Hz, of the modes ``modes`` (1-based; default 1..n).
    sigma_f_Hz, sigma_f_rel : absolute (Hz, e.g. FFT line spacing) and relative parts of the 1-sigma
    frequency uncertainty, combined in quadrature; they only rank the modes and give sigma(ln k_n).
    Raises :class:`ContactIdError` naming the frequency when no beta >= 0 can produce it.
    """
    f = np.atleast_1d(np.asarray(frequencies_Hz, dtype=float))
    if f.ndim != 1 or f.size == 0 or np.any(~np.isfinite(f)) or np.any(f <= 0):
        raise ContactIdError(f"frequencies = {np.asarray(frequencies_Hz).tolist()}; expected finite values > 0 Hz")
    modes = np.arange(1, f.size + 1) if modes is None else _check_modes(modes)
    if modes.size != f.size:
        raise ContactIdError(f"{f.size} frequencies but {modes.size} mode numbers; expected one mode number per frequency")
    if sigma_f_Hz < 0 or sigma_f_rel < 0 or (sigma_f_Hz == 0 and sigma_f_rel == 0):
        raise ContactIdError(f"frequency uncertainty sigma_f_Hz = {sigma_f_Hz}, sigma_f_rel = {sigma_f_rel}; "
                             "expected both >= 0 and not both 0")
    unit = bar.hz_per_unit_x()
    x = f / unit
    lo, hi = (modes - 1) * np.pi, (modes - 0.5) * np.pi
    bad = np.flatnonzero((x <= lo) | (x >= hi))
    if bad.size:
        j = bad[0]
        raise ContactIdError(
            f"frequency {f[j]:.6g} Hz of mode {modes[j]} lies outside ({lo[j] * unit:.6g}, {hi[j] * unit:.6g}) Hz, "
            f"the range of mode {modes[j]} for 0 < k_n < inf with this bar (l = {bar.length_m} m, c = {bar.wave_speed_m_s:.1f} m/s); "
            "hint: check the mode numbering or the bar data")
    beta = x * np.tan(x)
    k = beta * bar.structure_stiffness_N_m
    s = log_sensitivity(beta, x)
    sigma_f = np.hypot(sigma_f_Hz, sigma_f_rel * f)
    with np.errstate(divide="ignore"):
        sigma_ln_k = (sigma_f / f) / s
    best = int(np.argmin(sigma_ln_k))
    log.debug("normal identification: beta=%s k_n=%s S=%s best mode %d", beta, k, s, modes[best])
    return NormalIdentification(modes=modes, frequencies_Hz=f, x=x, beta=beta, k_n_N_m=k, sensitivity=s,
                                df_dlnk_Hz=s * f, sigma_ln_k=sigma_ln_k, best=best)
