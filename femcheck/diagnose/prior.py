"""The parameter prior of every effect: what the Laplace evidence integrates over and what the calibration bench
draws its hidden truths from.

Each fitted parameter p of an effect has, in the optimizer's scaled coordinate x = ``Param.to_x(value)`` (log10 of
the value for ``Param.log`` parameters, value / ``Param.typical`` otherwise), an independent normal prior

    x ~ N(mu, w^2) truncated to [to_x(lower), to_x(upper)],

with w = ``Param.prior_sd`` and mu = to_x(``Param.prior_center``), or the effect's neutral value for the model
(``Effect.neutral``: a leg factor 1, a gap 0, a scale 1 of a modelled element) when no centre is given. A parameter
whose neutral value is its bound (a gap >= 0, a friction force >= 0, a leg factor >= 1) has a half-normal prior.
The widths are of the order of half the magnitude of each effect's usual test value (``Effect.sample_truth``), so
that the prior spans "not there" to "clearly there":

=========================  =====================================  =========================  =================
effect                     parameter                              centre                     w (scaled units)
=========================  =====================================  =========================  =================
actuation_compliance       scale                                  neutral (1 if modelled)    1.0
joint_contact_compliance   scale                                  neutral                    2.0
hertz_stiffening           extra_compliance_at_ref                0 (half-normal)            4.0
joint_rotation_release     compliance_rad_per_Nm (log10)          0.1 rad/(N m)              1.0 decade
leg_softening              leg0..leg5                             1 (half-normal)            2.0
link_modulus               E_factor (log10)                       1                          0.25 decade
friction_hysteresis        friction_N (typical 5 N)               0 (half-normal)            2.0 (10 N)
sensor_misalignment        theta_x/y/z_rad (typical 0.05 rad)     0                          3.0 (0.15 rad)
clearance                  gap_x/y/z_m (typical 10 um)            0 (half-normal)            5.0 (50 um)
clearance                  closing_force_N                        4 N                        4.0 (4 N)
missing_compliance         three element scales                   0 (half-normal)            1.0
<element>_in_legs          leg factors of the placed legs         neutral                    1.0
=========================  =====================================  =========================  =================

A located effect's placement (k legs of 6) has the prior 1 / C(6, k) per subset (its extended-BIC term,
``ElementInLegs.penalty``), i.e. every number of legs is equally likely; :func:`draw_truth` draws k uniformly in 1..6
(all six legs is a placement like the others: the element changed in every leg).
"""
from __future__ import annotations

import dataclasses

import numpy as np
from scipy import stats


@dataclasses.dataclass(frozen=True)
class ParamPrior:
    """Prior of the parameters of one effect in scaled coordinates: ``mu``, ``sd``, bounds ``lo``, ``hi`` (k,)."""

    mu: np.ndarray
    sd: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    @property
    def mass(self) -> np.ndarray:
        """(k,) prior mass of the untruncated normal inside the bounds (1 / the truncation's density factor)."""
        return stats.norm.cdf((self.hi - self.mu) / self.sd) - stats.norm.cdf((self.lo - self.mu) / self.sd)


def _x_bound(p, v: float) -> float:
    if p.log and v <= 0:
        return -np.inf
    return float(p.to_x(v))


def effect_prior(effect, model) -> ParamPrior:
    """The prior of ``effect``'s parameters for ``model`` (module docstring)."""
    neutral = np.asarray(effect.neutral(model), float)
    mu, sd, lo, hi = [], [], [], []
    for p, n in zip(effect.params, neutral):
        c = p.prior_center if p.prior_center is not None else n
        lo_x, hi_x = _x_bound(p, p.lower), _x_bound(p, p.upper)
        m = _x_bound(p, c)
        if not np.isfinite(m):          # a log parameter whose neutral value is 0: centre on its start
            m = float(p.to_x(p.start))
        mu.append(float(np.clip(m, lo_x, hi_x)))
        sd.append(float(p.prior_sd))
        lo.append(lo_x)
        hi.append(hi_x)
    return ParamPrior(*(np.array(a, float) for a in (mu, sd, lo, hi)))


def fit_prior(effects, model) -> ParamPrior:
    """The prior of the concatenated parameters of ``effects`` (the order of a joint fit)."""
    parts = [effect_prior(e, model) for e in effects]
    if not parts:
        z = np.zeros(0)
        return ParamPrior(z, z, z, z)
    return ParamPrior(*(np.concatenate([getattr(q, f) for q in parts]) for f in ("mu", "sd", "lo", "hi")))


def draw_values(effect, model, rng) -> dict[str, float]:
    """Parameter values (natural units) of ``effect`` drawn from its prior (truncated normal, by inversion)."""
    q = effect_prior(effect, model)
    a, b = stats.norm.cdf((q.lo - q.mu) / q.sd), stats.norm.cdf((q.hi - q.mu) / q.sd)
    u = a + rng.uniform(size=len(q.mu)) * (b - a)
    x = q.mu + q.sd * stats.norm.ppf(np.clip(u, 1e-300, 1 - 1e-16))
    x = np.clip(x, q.lo, q.hi)
    return {p.name: float(np.clip(p.from_x(xi), p.lower, p.upper)) for p, xi in zip(effect.params, x)}


def draw_truth(effect, model, rng):
    """(effect id, {param: value}) of a hidden truth drawn from the prior: for a located effect (``Effect.located``)
    first the legs (k uniform in 1..6, then k legs uniformly), then their values."""
    if getattr(effect, "located", False):
        k = int(rng.integers(1, 7))
        legs = sorted(int(i) for i in rng.choice(6, size=k, replace=False))
        effect = effect.restricted(legs)
    return effect.id, draw_values(effect, model, rng)


__all__ = ["ParamPrior", "draw_truth", "draw_values", "effect_prior", "fit_prior"]
