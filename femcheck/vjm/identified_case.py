"""The identified joint springs of a serial robot written into a copy of its case (``identify --extended-case``).

Seed 002's least squares (eq. 10) gives compliances c (rad/(N m)): per joint the torsion (conventional model), or
torsion and the two tilts (extended model, order [torsion, tilt x, tilt y] per joint). The copy holds their
inverses as ``stiffness_Nm_per_rad`` and ``tilt_stiffness_Nm_per_rad``, each with a comment giving the 95 % interval
(c +- 1.96 standard errors, inverted) and the identification that set it. A conventional identification leaves the
tilt springs as they were. A joint given by a drive train, or an identified compliance that is not positive (a
spring the data could not resolve), is refused by name: the case has no key for it.
"""
from __future__ import annotations

import numpy as np

from femcheck.case.toml_edit import Edit, edited
from femcheck.errors import FemcheckError


def _stiffness_ci(c: float, se: float) -> str:
    lo, hi = c - 1.96 * se, c + 1.96 * se
    top = "inf" if lo <= 0 else f"{1.0 / lo:.6g}"
    return f"[{1.0 / hi:.6g}, {top}]"


def identified_case_text(case, case_text: str, compliance: np.ndarray, standard_error: np.ndarray, extended: bool,
                         data_path: str) -> str:
    """``case_text`` with the identified springs (module docstring)."""
    c, se = np.asarray(compliance, float), np.asarray(standard_error, float)
    per = 3 if extended else 1
    src = f"identify {'extended' if extended else 'conventional'} VJM on {data_path}"
    edits = []
    for i, j in enumerate(case.joints):
        name = j.name or f"joint {i + 1}"
        if j.drive_train is not None:
            raise FemcheckError(f"--extended-case: joint {name} is given by its drive train; the identified torsion "
                                "stiffness has no key beside it (replace the drive train by stiffness_Nm_per_rad)")
        ci, si = c[per * i:per * i + per], se[per * i:per * i + per]
        if np.any(ci <= 0):
            raise FemcheckError(f"--extended-case: joint {name}: identified compliance {ci.min():.3g} rad/(N m) is not "
                                "positive (the data do not resolve this spring); no stiffness to write")
        edits.append(Edit("joints", "stiffness_Nm_per_rad", float(1.0 / ci[0]),
                          f"95 % {_stiffness_ci(ci[0], si[0])} N m/rad from {src}", index=i))
        if extended:
            edits.append(Edit("joints", "tilt_stiffness_Nm_per_rad", [float(1.0 / ci[1]), float(1.0 / ci[2])],
                              f"95 % x {_stiffness_ci(ci[1], si[1])}, y {_stiffness_ci(ci[2], si[2])} N m/rad from {src}",
                              index=i))
    return edited(case_text, edits, "--extended-case")


def weights_case_text(case, case_text: str, results: dict, data_path: str) -> str:
    """``case_text`` with seed 001's identified weights as ``[fitting] weights`` (the links' stiffness scaled by
    them under the case's reading of eq. 10, ``[fitting] stiffness_scaling``): the fit of both setups together when the data hold both, else the one setup's. Weights the case
    already held are multiplied by the fitted ones (the fit was relative to them); the comment gives each weight's
    95 % interval and names the unidentifiable ones (their value is the fit's, not a measurement)."""
    name = "D/F + F/D" if "D/F + F/D" in results else next(iter(results))
    g = results[name]
    held = np.ones(case.fitting.n_weights) if case.fitting.weights is None else np.asarray(case.fitting.weights, float)
    w = held * np.asarray(g["weights"], float)
    def interval(k, lo, hi):
        span = "no interval" if lo is None or hi is None else f"[{held[k] * lo:.4g}, {held[k] * hi:.4g}]"
        return f"W{k + 1} {span}" + (" unidentifiable" if f"W{k + 1}" in g["unidentifiable"] else "")
    ci = "; ".join(interval(k, lo, hi) for k, (lo, hi) in enumerate(zip(g["ci95_low"], g["ci95_high"])))
    edit = Edit("fitting", "weights", [float(v) for v in w],
                f"95 %: {ci}; from identify (seed 001 weight fit, setup {name}) on {data_path}")
    return edited(case_text, [edit], "--extended-case")
