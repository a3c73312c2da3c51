"""Residual analysis of a model against measured readings.

Error metric (docs/conventions.md §9, seed 000 Tables 2/3): per point and load direction the eq. 1 deflection
delta = delta_t - delta_p of model and measurement; the *along-load* relative error
``|u.(delta_model - delta_meas)| / |u.delta_meas|`` (the seed's) and the *vector* relative error
``|delta_model - delta_meas| / |delta_meas|`` (also counts axis cross-talk, our default for the held-out
error). Errors are averaged over points per axis (x, y, z or the named load case) and overall.

Signatures, each a number with its noise level (standard error from the reading uncertainty) and a
z-score; ``|z| > 3`` flags it:

* ``scale``: mean of the deflection ratio rho = u.delta_meas / u.delta_model minus 1 (all cases);
* ``direction:<axis>``: mean rho per axis minus the overall mean (direction-specific error);
* ``nonlinearity``: mean over cases of the measured minus the model's ratio of preload secant
  compliance to test-load compliance, (delta_p / P_p) / (delta / P_T) (> 0: the device stiffens with load
  more than the model, < 0: softens);
* ``offset``: mean intercept delta_p - P_p delta / P_T (dead band / offset closed by the preload), measured
  minus model, m;
* ``hysteresis``: mean unload-minus-preload reading at P_p plus the residual reading at zero load, measured
  minus model, along the load, m;
* ``leg_asymmetry``: the device is mirror-symmetric in y (docs/conventions.md §2): mean |rho(P) - rho(mirror P)|
  over mirrored pairs (P1/P4, P2/P3, P5/P8, P6/P7) for x and z loads;
* ``cross_talk``: rms of the off-load components of delta_meas - delta_model relative to |delta_meas|.
"""
from __future__ import annotations

import dataclasses

import numpy as np

MIRROR_PAIRS = (("P1", "P4"), ("P2", "P3"), ("P5", "P8"), ("P6", "P7"))
_FLAG_Z = 3.0


def case_deltas(readings, predicted_states: np.ndarray) -> np.ndarray:
    """(c, 3) eq. 1 deflection of a model from its predicted state readings (m, 3)."""
    return predicted_states[readings.total_state] - predicted_states[readings.preload_state]


def case_errors(readings, delta_model: np.ndarray) -> dict[str, np.ndarray]:
    """Per-case relative errors: ``vector`` and ``along`` (c,), fractions."""
    dm, u = readings.delta, readings.case_unit
    vec = np.linalg.norm(delta_model - dm, axis=1) / np.linalg.norm(dm, axis=1)
    along = np.abs(np.einsum("ij,ij->i", delta_model - dm, u)) / np.abs(np.einsum("ij,ij->i", dm, u))
    return {"vector": vec, "along": along}


def mean_by_axis(readings, err: np.ndarray, select=None) -> dict[str, float]:
    """Mean of per-case ``err`` (c,) per axis (x, y, z / named load case) and ``overall`` (over axes' means' cases)."""
    axes = readings.case_axis()
    sel = np.ones(len(err), bool) if select is None else np.asarray(select, bool)
    out = {a: float(np.mean(err[sel & (axes == a)])) for a in dict.fromkeys(axes.tolist()) if np.any(sel & (axes == a))}
    out["overall"] = float(np.mean(err[sel]))
    return out


def mean_by_direction(readings, err: np.ndarray) -> dict[str, float]:
    """Mean of per-case ``err`` (c,) per signed load direction (+x, -x, ... or the named load case)."""
    d = readings.case_direction
    return {k: float(np.mean(err[d == k])) for k in dict.fromkeys(d.tolist())}


def error_table(readings, delta_model: np.ndarray, metric: str = "along") -> dict:
    """Seed 000 Table 2/3 layout: {axis: {point: error %, ..., 'Average': %}}, averaged over +/- directions."""
    err = case_errors(readings, delta_model)[metric] * 100.0
    axes = readings.case_axis()
    table = {}
    for a in dict.fromkeys(axes.tolist()):
        row = {}
        for p in readings.points:
            s = (axes == a) & (readings.case_point == p)
            if s.any():
                row[p] = float(err[s].mean())
        row["Average"] = float(np.mean(list(row.values())))
        table[a] = row
    return table


@dataclasses.dataclass(frozen=True)
class Signature:
    name: str
    value: float
    noise: float
    unit: str
    meaning: str

    @property
    def z(self) -> float:
        return self.value / self.noise if self.noise > 0 else float("inf") * np.sign(self.value)

    @property
    def flagged(self) -> bool:
        return bool(abs(self.z) > _FLAG_Z)

    def as_dict(self) -> dict:
        return {"name": self.name, "value": self.value, "noise": self.noise, "z": float(self.z), "unit": self.unit,
                "flagged": self.flagged, "meaning": self.meaning}


def signatures(readings, predicted_states: np.ndarray) -> list[Signature]:
    """Residual signatures of the model readings ``predicted_states`` (m, 3) against ``readings``."""
    sig_r = readings.reading_sigma_m
    u = readings.case_unit
    dmod = case_deltas(readings, predicted_states)
    dm_a = np.einsum("ij,ij->i", readings.delta, u)
    dmod_a = np.einsum("ij,ij->i", dmod, u)
    sd_a = readings.delta_sigma[:, 0]
    rho = dm_a / dmod_a
    sd_rho = np.abs(sd_a / dmod_a)
    c = len(rho)
    out = [Signature("scale", float(rho.mean() - 1.0), float(np.sqrt(np.sum(sd_rho ** 2)) / c), "-",
                     "measured / model deflection - 1 (all points and directions)")]
    axes = readings.case_axis()
    for a in dict.fromkeys(axes.tolist()):
        s = axes == a
        out.append(Signature(f"direction:{a}", float(rho[s].mean() - rho.mean()),
                             float(np.sqrt(np.sum(sd_rho[s] ** 2)) / s.sum()), "-",
                             f"ratio along {a} minus the overall ratio (direction-specific error)"))
    pre = readings.preload_state
    Pp, PT = readings.preload_N, readings.test_N
    dp_m = np.einsum("ij,ij->i", readings.disp[pre], u)
    dp_mod = np.einsum("ij,ij->i", predicted_states[pre], u)
    ok = (Pp > 0) & (np.abs(dm_a) > 0) & (np.abs(dmod_a) > 0)
    if ok.any():
        nl_m = (dp_m[ok] / Pp[ok]) / (dm_a[ok] / PT[ok])
        nl_mod = (dp_mod[ok] / Pp[ok]) / (dmod_a[ok] / PT[ok])
        sd_nl = np.abs(nl_m) * np.sqrt((readings.sigma[pre[ok], 0] / np.maximum(np.abs(dp_m[ok]), 1e-300)) ** 2
                                       + (sd_a[ok] / np.abs(dm_a[ok])) ** 2)
        out.append(Signature("nonlinearity", float(np.mean(nl_m - nl_mod)), float(np.sqrt(np.sum(sd_nl ** 2)) / ok.sum()),
                             "-", "preload secant / test-load compliance, measured minus model (>0 stiffening)"))
        off_m = dp_m - Pp * dm_a / PT
        off_mod = dp_mod - Pp * dmod_a / PT
        sd_off = np.sqrt(readings.sigma[pre, 0] ** 2 + (Pp / PT * sd_a) ** 2)
        out.append(Signature("offset", float(np.mean((off_m - off_mod)[ok])), float(np.sqrt(np.sum(sd_off[ok] ** 2)) / ok.sum()),
                             "m", "preload reading minus linear extrapolation, measured minus model (dead band)"))
    unl = np.flatnonzero(readings.phase == "unload")
    if unl.size:
        ci = readings.case_index[unl]
        keep = ci >= 0
        unl, ci = unl[keep], ci[keep]
        a_m = np.einsum("ij,ij->i", readings.disp[unl], u[ci])
        a_mod = np.einsum("ij,ij->i", predicted_states[unl], u[ci])
        ref_m = np.where(readings.load_N[unl] != 0, np.einsum("ij,ij->i", readings.disp[pre[ci]], u[ci]), 0.0)
        ref_mod = np.where(readings.load_N[unl] != 0, np.einsum("ij,ij->i", predicted_states[pre[ci]], u[ci]), 0.0)
        h = (a_m - ref_m) - (a_mod - ref_mod)
        out.append(Signature("hysteresis", float(h.mean()), float(np.sqrt(2.0) * sig_r / np.sqrt(readings.n_trials[unl].mean())
                                                                   / np.sqrt(h.size)), "m",
                             "unloading minus loading reading, measured minus model (friction)"))
    diffs, sds = [], []
    for a, b in MIRROR_PAIRS:
        for ax in ("x", "z"):
            ia = np.flatnonzero((readings.case_point == a) & (axes == ax))
            ib = np.flatnonzero((readings.case_point == b) & (axes == ax))
            if ia.size and ib.size:
                diffs.append(rho[ia].mean() - rho[ib].mean())
                sds.append(np.sqrt(np.mean(sd_rho[ia] ** 2) / ia.size + np.mean(sd_rho[ib] ** 2) / ib.size))
    if diffs:
        diffs, sds = np.abs(np.array(diffs)), np.array(sds)
        # E|N(0, s)| = s sqrt(2/pi): compare the mean absolute difference with what noise alone gives
        out.append(Signature("leg_asymmetry", float(diffs.mean() - np.mean(sds) * np.sqrt(2 / np.pi)),
                             float(np.sqrt(np.sum(sds ** 2)) / len(sds)), "-",
                             "mirror-point ratio difference beyond noise (a leg softer than its mirror)"))
    off = (readings.delta - dmod) - np.einsum("ij,ij->i", readings.delta - dmod, u)[:, None] * u
    ct = float(np.sqrt(np.mean(np.sum(off ** 2, axis=1) / np.sum(readings.delta ** 2, axis=1))))
    ct_noise = float(np.sqrt(np.mean(2 * readings.delta_sigma[:, 0] ** 2 / np.sum(readings.delta ** 2, axis=1))))
    out.append(Signature("cross_talk", ct - ct_noise, ct_noise / np.sqrt(c), "-",
                         "off-load residual components / |delta| beyond noise (misaligned dials, coupling)"))
    return out
