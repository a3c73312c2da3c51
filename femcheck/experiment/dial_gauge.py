"""A dial-gauge stiffness campaign written without the diagnosis's effect code (a check of the diagnosis).

The virtual experiment of :mod:`femcheck.experiment.simulate` hides a cause by applying the diagnosis's own effect
functions, so a diagnosis run on it meets the functional form it fits. This generator builds the world from the
device model instead:

- **link modulus**: the aluminium's Young's modulus is changed in the case itself (``materials.aluminium.E_Pa``), so
  the guideways, the proximal links *and* the U-joint yoke bores (a line contact, a law the effect does not scale)
  all follow it;
- **weak guideway**: the guideway compliance of one leg is multiplied in the chain model
  (``femcheck.chain.evaluate``'s element scales);
- **changed case parameters** (``case_params``, {dotted case key: value}): any section, pin, cable or material value
  of the case, changed in the case itself (``Case.with_params``), so every element formula that reads it follows
  (e.g. a thinner U-joint pin changes both its bending and its line contact; a thinner guideway both bending axes);
- **element scales** (``element_scale``, {element key of ``femcheck.chain.ELEMENTS``: factor, or (6,) factors per
  leg}): an element's compliance multiplied in the chain model, e.g. the proximal links' for a tube of half the
  modulus (a cantilever's compliance is 1/E, and 1/G at a fixed Poisson ratio);
- **sensor misalignment**: the dial frame is rotated by a rotation vector (``scipy.spatial.transform.Rotation``);
- **another device** (``device``): the translations come from that world instead of the chain, e.g. the device FE
  of a changed case (:mod:`femcheck.experiment.device_fe_world`); friction and the sensor frame still apply;
- **friction**: Coulomb friction F_f at the TCP acting along the load direction: the force that deflects the device
  on loading is |F| - F_f; on unloading the device sticks at its peak deflection until the load has dropped by
  2 F_f (a stick band of width 2 F_f around the loading curve), then follows |F| + F_f.

The readings are those of dial gauges: every reading is the true TCP translation plus Gaussian scatter
``scatter_m`` (independent per reading and axis), rounded to the dial step ``resolution_m``, over ``trials`` trials
of the protocol (:func:`femcheck.experiment.simulate.protocol_rows`). ``snr`` sets a cause's magnitude: the RMS over
the loaded readings of the change it makes to the model's deflection is ``snr`` x ``scatter_m``.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial.transform import Rotation

from femcheck.chain import ChainAdjustments, ELEMENTS, evaluate
from femcheck.experiment.simulate import protocol_rows
from femcheck.measured.csv_format import AXIS_DIRECTIONS, MeasuredData, format_measured_csv, parse_measured_csv
from femcheck.measured.protocol import resolve_poses

#: the causes this generator can hide, with the vocabulary id the diagnosis should name
CAUSES = {"link_modulus": "link_modulus", "weak_guideway": "guideway_in_legs",
          "sensor_misalignment": "sensor_misalignment", "friction": "friction_hysteresis"}


@dataclasses.dataclass(frozen=True)
class DialCampaign:
    """``data`` the readings as read back from CSV; ``truth`` {cause: magnitude} hidden in them."""

    data: MeasuredData
    truth: dict


def _true_translation(case, pose, force, *, modulus: float, guideway_leg: int | None, guideway: float,
                      joints: str, case_params: dict | None = None, element_scale: dict | None = None) -> np.ndarray:
    """(r, 3) TCP translation (m) of the device under ``force`` (r, 3) N at ``pose`` (r, 6)."""
    if modulus != 1.0:
        E = next(m.E_Pa for m in case.materials if m.name == "aluminium")
        case = case.with_params(**{"materials.aluminium.E_Pa": E * modulus})
    if case_params:
        case = case.with_params(**case_params)
    scale = np.ones((6, len(ELEMENTS)))
    for element, factor in (element_scale or {}).items():
        scale[:, ELEMENTS.index(element)] *= np.broadcast_to(np.asarray(factor, float), (6,))
    if guideway_leg is not None:
        scale[guideway_leg, ELEMENTS.index("lg")] *= guideway
    W = np.zeros((len(pose), 6))
    W[:, :3] = force
    r = evaluate(case, pose, W, model="detailed", joints=joints, adjust=ChainAdjustments(element_scale=scale))
    return r.twist[:, :3]


def _deflecting_force(force, load, phase, point, direction, trial, friction_N: float) -> np.ndarray:
    """(r, 3) force that deflects the device under Coulomb friction ``friction_N`` at the TCP (module docstring)."""
    if friction_N <= 0.0:
        return force
    F = np.abs(load)
    peak = np.zeros_like(F)
    # the peak of each (point, direction, trial) load cycle, its total load: the unload steps stick relative to it
    # (the preload-identification staircase at P0 comes after the cycle and does not count)
    key = np.array([f"{p}|{d}|{t}" for p, d, t in zip(point, direction, trial)])
    for k in np.unique(key):
        sel = key == k
        peak[sel] = F[sel & (phase == "total")].max(initial=0.0)
    eff = np.where(phase == "unload", np.minimum(peak - friction_N, F + friction_N), F - friction_N)
    eff = np.maximum(eff, 0.0)
    unit = np.zeros_like(force)
    nz = F > 0
    unit[nz] = force[nz] / F[nz, None]
    # unloaded to zero: the stuck deflection keeps the direction of the load it came from
    unit[~nz] = np.array([AXIS_DIRECTIONS[d] for d in direction[~nz]], float)
    return unit * eff[:, None]


def _world(case, rows, poses, causes: dict, joints: str) -> np.ndarray:
    point, direction, trial, phase, load, force = rows
    f = _deflecting_force(force, load, phase, point, direction, trial, causes.get("friction", 0.0))
    leg = causes.get("weak_guideway_leg")
    if causes.get("device") is not None:   # a world of its own (e.g. a device FE), not the chain of the case
        return _rotated(causes["device"].tcp_displacement(poses, f), causes)
    d = _true_translation(case, poses, f, modulus=causes.get("link_modulus", 1.0), guideway_leg=leg,
                          guideway=causes.get("weak_guideway", 1.0), joints=joints,
                          case_params=causes.get("case_params"), element_scale=causes.get("element_scale"))
    return _rotated(d, causes)


def _rotated(d, causes: dict) -> np.ndarray:
    theta = causes.get("sensor_misalignment")
    if theta is not None:
        d = d @ Rotation.from_rotvec(np.asarray(theta, float)).as_matrix().T
    return d


def _change_rms(case, rows, poses, causes: dict, joints: str, nominal: np.ndarray | None = None) -> float:
    """RMS over the total readings of the change ``causes`` make to the deflection (total - preload), m, against the
    readings ``nominal`` (default: the case's chain)."""
    phase = rows[3]
    tot, pre = np.flatnonzero(phase == "total"), np.flatnonzero(phase == "preload")
    nominal = _world(case, rows, poses, {}, joints) if nominal is None else nominal
    world = _world(case, rows, poses, causes, joints)
    change = (world[tot] - world[pre]) - (nominal[tot] - nominal[pre])
    return float(np.sqrt(np.mean(np.sum(change ** 2, axis=1))))


def _magnitude_at_snr(case, rows, poses, causes: dict, name: str, target_m: float, joints: str) -> dict:
    """``causes`` with cause ``name``'s magnitude set so that its own change of the deflection has RMS ``target_m``
    (secant steps on the magnitude; the change is nearly linear in it)."""
    def with_mag(a):
        c = dict(causes)
        if name == "sensor_misalignment":
            c[name] = a * np.asarray(causes[name], float) / np.linalg.norm(causes[name])
        elif name == "friction":
            c[name] = a
        else:   # a factor: 1 + a
            c[name] = 1.0 + a if name != "link_modulus" else 1.0 / (1.0 + a)
        return c
    only = {k: v for k, v in causes.items() if k in (name, "weak_guideway_leg")}
    a0, a1 = 0.0, {"sensor_misalignment": 0.01, "friction": 1.0}.get(name, 0.1)
    r0 = 0.0
    for _ in range(6):
        r1 = _change_rms(case, rows, poses, {k: v for k, v in with_mag(a1).items() if k in only}, joints)
        if abs(r1 - target_m) < 0.02 * target_m or r1 == r0:
            break
        a0, a1, r0 = a1, a1 + (target_m - r1) * (a1 - a0) / (r1 - r0), r1
    return with_mag(a1)


def _protocol(case, directions, trials: int, sweep: bool):
    """The campaign's reading rows and their poses."""
    rows = protocol_rows(case, directions, trials, sweep)
    point, direction, trial, phase, load, force = rows
    n = len(point)
    blank = MeasuredData(source="<dial campaign>", point=point, direction=direction, trial=trial, phase=phase,
                         load_N=load, force=force, disp=np.zeros((n, 3)), row=np.arange(2, n + 2))
    return rows, resolve_poses(blank, case)


def device_change_rms(case, worlds, reference, *, directions=("+x", "+y", "+z"), trials: int = 3,
                      sweep: bool = True) -> np.ndarray:
    """(len(worlds),) RMS (m) over the campaign's total readings of the change of the deflection (total - preload)
    from the device world ``reference`` to each of ``worlds`` (each with ``tcp_displacement(pose, force)``),
    noise-free: the signal of a physical change, to set against the reading scatter (its signal-to-noise ratio,
    module docstring)."""
    rows, poses = _protocol(case, directions, trials, sweep)
    nominal = _world(case, rows, poses, {"device": reference}, "rigid")
    return np.array([_change_rms(case, rows, poses, {"device": w}, "rigid", nominal) for w in worlds])


def dial_campaign(case, causes: dict, *, seed: int, snr: float | dict | None = None, trials: int = 3,
                  resolution_m: float = 1e-5, scatter_m: float = 3e-6, directions=("+x", "+y", "+z"),
                  sweep: bool = True, joints: str = "rigid") -> DialCampaign:
    """Readings of a dial-gauge campaign on the device with hidden ``causes`` (module docstring).

    ``causes``: {"link_modulus": E_true / E_case, "weak_guideway": compliance factor, "weak_guideway_leg": leg index,
    "sensor_misalignment": (3,) rotation vector rad, "friction": N, "case_params": {case key: value},
    "element_scale": {element: factor or (6,) factors}, "device": a world with ``tcp_displacement(pose, force)``
    that replaces the chain, e.g. :class:`femcheck.experiment.device_fe_world.DeviceFEWorld`} (the last three are
    not rescaled by ``snr``). ``snr``: a number (or {cause: number}) that
    rescales each named cause to that signal-to-noise ratio (the sensor rotation keeps its axis). Seeded."""
    rng = np.random.default_rng(seed)
    rows, poses = _protocol(case, directions, trials, sweep)
    point, direction, trial, phase, load, force = rows
    causes = dict(causes)
    if snr is not None:
        for name in [k for k in causes if k in CAUSES]:
            s = snr.get(name) if isinstance(snr, dict) else snr
            if s is not None:
                causes = _magnitude_at_snr(case, rows, poses, causes, name, s * scatter_m, joints)
    d = _world(case, rows, poses, causes, joints)
    read = d + rng.normal(0.0, scatter_m, size=d.shape)
    read = resolution_m * np.round(read / resolution_m)
    text = format_measured_csv(point, direction, trial, phase, load, force, read, resolution_m=resolution_m,
                               meta={"case": case.meta.name, "case_sha256": case.sha256, "source": "dial campaign"})
    truth = {k: (np.asarray(v, float).tolist() if k == "sensor_misalignment" else
                 {e: np.asarray(f, float).tolist() for e, f in v.items()} if k == "element_scale" else v)
             for k, v in causes.items() if k != "device"}
    return DialCampaign(data=parse_measured_csv(text, "<dial campaign>"), truth=truth)
