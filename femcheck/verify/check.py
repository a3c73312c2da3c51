"""Checks of a verification run: drift against the baselines and the analytical-FE error thresholds.

Every check is a :class:`Check` (name, status ``pass | fail | skipped``, one-line detail); the report's
verdict, ``verdict.json`` and ``junit.xml`` list them all (:mod:`femcheck.verify.render`).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.verify.analytical import JOINTS
from femcheck.verify.baseline import compare, load_baseline, save_baseline

#: analytical values may only drift by round-off (the model is closed-form)
ANALYTICAL_RTOL = 1e-9
#: FE values: deterministic structured meshes; direct solvers differ by round-off only (1e-10 seen),
#: so 1e-6 flags any real change of mesh, model or solver while tolerating BLAS/thread differences
FE_RTOL = 1e-6
#: mean relative error analytical vs FE per direction and idealization that --check accepts (issue 6)
ERROR_THRESHOLDS = {"simplified": 0.05, "detailed": 0.10}


@dataclasses.dataclass(frozen=True)
class Check:
    """One check of the run: ``status`` is "pass", "fail" or "skipped"; ``detail`` says what was compared."""

    name: str
    status: str
    detail: str = ""


def average_row(tab) -> dict:
    """The ``average`` row of an error table, without its ``point`` column ({"+x error %": value, ...})."""
    return {k: v for k, v in next(r for r in tab if r["point"] == "average").items() if k != "point"}


def followed_idealization(tabs: dict) -> str | None:
    """The analytical idealization the contact FE follows: the one with the smaller mean error over the
    directions (``tabs`` keyed (level, joints) or (level, joints, fe_joints))."""
    cand = {j: np.mean(list(average_row(tabs[("detailed", j, "contact")]).values()))
            for j in JOINTS if ("detailed", j, "contact") in tabs}
    return min(cand, key=cand.get) if cand else None


#: the idealization the contact-joint FE is expected to follow, stated before it runs: joints that can turn
#: (ball in seat, pins in bores) carry only their friction moment (CONVENTIONS.md §5, "A solid FE model with
#: real ball-in-seat and pin-in-bore contact ... should side with released")
EXPECTED_CONTACT_IDEALIZATION = "released"


def threshold_checks(tables_by_level: dict, expected: str = EXPECTED_CONTACT_IDEALIZATION) -> list[Check]:
    """A check per (level, joints, direction) mean error against ERROR_THRESHOLDS[level]: the matching
    idealizations, and the contact FE against the ``expected`` idealization (stated before the run, not
    chosen after it); plus one check that the contact FE follows ``expected`` rather than another one."""
    out = []
    followed = followed_idealization(tables_by_level)
    if followed is not None:
        ok = followed == expected
        out.append(Check("contact FE follows the expected idealization", "pass" if ok else "fail",
                         f"contact-joint FE expected to follow '{expected}', follows '{followed}'"))
    for key, tab in tables_by_level.items():
        level, joints = key[:2]
        contact = len(key) == 3 and key[2] != joints
        if contact and joints != expected:
            continue  # contact FE vs the idealization it is not expected to follow: informative only
        name = f"{level}/{joints}" + (" vs contact FE" if contact else "")
        limit = 100 * ERROR_THRESHOLDS[level]
        for k, v in average_row(tab).items():
            ok = v <= limit
            out.append(Check(f"threshold {name} {k.split()[0]}", "pass" if ok else "fail",
                             f"{name} {k.split()[0]}: mean analytical-FE error {v:.2f} % {'<=' if ok else '>'} {limit:.0f} %"))
    return out


def threshold_failures(tables_by_level: dict) -> list[str]:
    """Lines for every (level, joints, direction) whose mean error exceeds its threshold."""
    return [c.detail for c in threshold_checks(tables_by_level) if c.status == "fail"]


def drift_check(name: str, current: dict[str, float], baseline_path, rtol: float, update: bool, check: bool) -> list[str]:
    """Drift lines of ``current`` against the baseline file (only the keys it shares with the run);
    ``update`` merges ``current`` into the file instead (the analytical baseline is replaced whole)."""
    if baseline_path is None:
        return []
    if update:
        merged = dict(load_baseline(baseline_path) or {}) if name == "FE baseline" else {}
        merged.update(current)
        save_baseline(baseline_path, merged)
        return []
    if not check:
        return []
    base = load_baseline(baseline_path)
    if base is None:
        return [f"{name} {baseline_path} not found (create it with --update-baseline)"]
    subset = {k: v for k, v in base.items() if k in current}
    return compare(current, subset, rtol) if subset else [f"{name} {baseline_path} has none of these keys"]


def drift_as_check(name: str, lines: list[str], ran: bool, rtol: float) -> Check:
    if not ran:
        return Check(name, "skipped", "no --check or no baseline given")
    if lines:
        return Check(name, "fail", f"{len(lines)} value(s) drifted: " + lines[0] + (" ..." if len(lines) > 1 else ""))
    return Check(name, "pass", f"no value drifted by more than {rtol:g} (relative)")
