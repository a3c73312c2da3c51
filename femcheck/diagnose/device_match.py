"""Do the measured data come from the device the case describes?

A diagnosis explains the differences between a model and *its* device. Data measured on another device
(another case file, a prototype with other dimensions, readings in the wrong unit) would be "explained" by
large, wrong effects. Two checks, each a warning (the data stay usable):

- **identity**: a ``# case_sha256:`` metadata line in the CSV (written by ``femcheck experiment simulate``)
  that differs from the case's hash;
- **scale**: the median ratio of measured to predicted deflection along the load, over the eq. 1 cases
  (total - preload) and separately over the preload readings (zeroed unloaded, so they scale with the
  device too), outside ``[1 / MAX_SCALE_RATIO, MAX_SCALE_RATIO]``. The model effects of the vocabulary
  change the compliance by tens of percent (README contributions), not by a factor of three.
"""
from __future__ import annotations

import numpy as np

from femcheck.diagnose.model import predict_readings

#: a device whose readings differ from the case's prediction by more than this factor looks like another device
MAX_SCALE_RATIO = 3.0


def _median_ratio(measured: np.ndarray, predicted: np.ndarray, unit: np.ndarray) -> float:
    m = np.einsum("ij,ij->i", measured, unit)
    p = np.einsum("ij,ij->i", predicted, unit)
    ok = np.abs(p) > 0
    return float(np.median(m[ok] / p[ok])) if ok.any() else float("nan")


def device_mismatch_warnings(case, data_meta: dict, readings, model) -> list[str]:
    """Warnings (possibly none) that ``readings`` (with CSV metadata ``data_meta``) were not measured on ``case``."""
    out = []
    sha = (data_meta or {}).get("case_sha256")
    if sha and sha != case.sha256:
        out.append(f"the data were made for case {data_meta.get('case') or '?'} (sha256 {sha[:12]}...), not for "
                   f"{case.meta.name} (sha256 {case.sha256[:12]}...): the device may differ")
    pred = predict_readings(model, readings)
    if len(readings.case_point):
        delta_pred = pred[readings.total_state] - pred[readings.preload_state]
        ratio = _median_ratio(readings.delta, delta_pred, readings.case_unit)
        if np.isfinite(ratio) and not (1 / MAX_SCALE_RATIO <= ratio <= MAX_SCALE_RATIO):
            out.append(f"measured deflections are {ratio:.3g}x the case's prediction (median over "
                       f"{len(readings.case_point)} cases): is this the device of {case.source}, and are the readings in mm?")
        pre = readings.preload_state
        ratio_pre = _median_ratio(readings.disp[pre], pred[pre], readings.case_unit)
        if np.isfinite(ratio_pre) and not (1 / MAX_SCALE_RATIO <= ratio_pre <= MAX_SCALE_RATIO) \
                and np.isfinite(ratio) and (1 / MAX_SCALE_RATIO <= ratio <= MAX_SCALE_RATIO):
            out.append(f"the preload readings are {ratio_pre:.3g}x the case's prediction at the preload while the "
                       "test increments match it: were the dials zeroed unloaded?")
    return out
