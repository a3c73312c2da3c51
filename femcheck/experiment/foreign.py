"""Out-of-vocabulary effects: plausible device errors that no diagnosis effect module can express. They test that a diagnosis says "unexplained" instead of naming the closest wrong cause.

Each acts on the noiseless readings d (r, 3) m of the protocol (:func:`femcheck.experiment.simulate.simulate`
with zero noise and resolution), per row, before noise and quantization are added:

* ``base_rocking``: the device's base mount rocks on a compliant bench about horizontal axes through the
  base origin: rotation theta = c (r x F)_xy (c rad / N m), reading += theta x r, r the TCP position (m).
  Pose- and height-dependent, couples directions; no element of the chain sits below the base.
* ``trial_creep``: the loaded readings creep with trial order: reading += eps (trial - 1) d for rows with
  a load (viscoelastic set of the slider bearings between trials); eps per trial.
* ``load_softening``: the device softens with load level: reading += a (|F| / F_T) d (a cubic term of the
  force-deflection curve; the vocabulary's Hertz effect only stiffens and its clearance only adds a dead band).
* ``dial_shear``: the dial stand shears symmetrically: x' = x + k z, z' = z + k x (a symmetric strain of
  the reading frame; the vocabulary's misalignment is a rotation, antisymmetric).

``magnitude`` is the dimensionless size: c is set so that the rocking displacement at P0 under the test
load along x is ``magnitude`` times the device's deflection there; eps, a and k are ``magnitude`` itself.
"""
from __future__ import annotations

import numpy as np

from femcheck.experiment.simulate import ALL_DIRECTIONS, VirtualExperiment, simulate
from femcheck.measured.csv_format import format_measured_csv, parse_measured_csv
from femcheck.measured.protocol import resolve_poses

FOREIGN = ("base_rocking", "trial_creep", "load_softening", "dial_shear")


def _rocking(d, pose, force, trial, load, test_N, magnitude):
    r = pose[:, :3]
    # reference: deflection magnitude of P0 (first row with the largest load along x) -> compliance c
    m = np.cross(r, force)
    m[:, 2] = 0.0
    ix = np.argmax(np.abs(force[:, 0]))
    theta_ref = np.cross(m[ix], r[ix])
    c = magnitude * np.linalg.norm(d[ix]) / max(np.linalg.norm(theta_ref), 1e-300)
    return d + c * np.cross(m, r)


def _creep(d, pose, force, trial, load, test_N, magnitude):
    loaded = (np.abs(load) > 0)[:, None]
    return d + loaded * magnitude * (trial - 1)[:, None] * d


def _softening(d, pose, force, trial, load, test_N, magnitude):
    return d + magnitude * (np.linalg.norm(force, axis=1) / test_N)[:, None] * d


def _shear(d, pose, force, trial, load, test_N, magnitude):
    out = d.copy()
    out[:, 0] += magnitude * d[:, 2]
    out[:, 2] += magnitude * d[:, 0]
    return out


_APPLY = {"base_rocking": _rocking, "trial_creep": _creep, "load_softening": _softening, "dial_shear": _shear}


def simulate_foreign(case, foreign: str, magnitude: float, *, hidden=(), seed: int = 0,
                     directions=ALL_DIRECTIONS, noise_sigma_m: float | None = None,
                     resolution_m: float | None = None, model=None, trials: int | None = None) -> VirtualExperiment:
    """Readings of the protocol with the out-of-vocabulary effect ``foreign`` (see module docstring) on top of
    the vocabulary effects ``hidden``, then Gaussian noise and quantization as in ``simulate``."""
    if foreign not in _APPLY:
        raise ValueError(f"unknown foreign effect {foreign!r}; expected one of {', '.join(FOREIGN)}")
    clean = simulate(case, hidden, seed=seed, directions=directions, noise_sigma_m=0.0, resolution_m=0.0,
                     model=model, trials=trials)
    data = clean.data
    pose = resolve_poses(data, case)
    d = _APPLY[foreign](data.disp, pose, data.force, np.asarray(data.trial, float), data.load_N,
                        float(case.loads.detailed_test_N), magnitude)
    rng = np.random.default_rng(seed + 7919)
    sigma = case.measurement.noise_sigma_m if noise_sigma_m is None else noise_sigma_m
    res = case.measurement.dial_resolution_m if resolution_m is None else resolution_m
    d = d + rng.normal(0.0, sigma, d.shape) if sigma > 0 else d
    if res > 0:
        d = res * np.round(d / res)
    text = format_measured_csv(data.point, data.direction, data.trial, data.phase, data.load_N, data.force, d,
                               resolution_m=res)
    truth = dict(clean.truth, foreign={"id": foreign, "magnitude": float(magnitude)}, noise_sigma_m=sigma,
                 dial_resolution_m=res, seed=seed)
    return VirtualExperiment(data=parse_measured_csv(text, "<virtual experiment, foreign>"), csv_text=text, truth=truth)


__all__ = ["FOREIGN", "simulate_foreign"]
