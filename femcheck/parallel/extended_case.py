"""The corrected parallel-device case: the kept candidate of :func:`femcheck.parallel.diagnosis.diagnose` written
into a copy of the case as ``[model.element_scale]`` (per element kind, one compliance factor per leg).

The device built from the copy multiplies every element scale by these factors
(:func:`femcheck.parallel.chain_model.evaluate`), so ``stiffness``, ``map`` and ``diagnose`` of the copy predict what
the fit predicted ("after"). Factors the case already held are multiplied by the fitted ones (the fit was relative to
them). Each written kind carries a comment: the legs the fit changed, their 95 % intervals, and the candidate.
"""
from __future__ import annotations

import numpy as np

from femcheck.case.toml_edit import edited, factor_table_edits


def extended_case_text(case, case_text: str, diagnosis) -> str:
    """``case_text`` with the kept candidate's factors (module docstring)."""
    dev = case.device
    names, legs = dev.element_names, [lg.name for lg in dev.legs]
    held = dev.element_scale if dev.element_scale is not None else np.ones((dev.n_legs, len(names)))
    new, (lo, hi) = diagnosis.scale, diagnosis.scale_ci
    edits = factor_table_edits("model.element_scale", names, legs, held, new, lo, hi, f"'{diagnosis.best.what}'")
    return edited(case_text, edits, "--extended-case")
