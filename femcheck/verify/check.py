"""Checks of a verification run and its verdict: the analytical-FE error thresholds, the idealization the
contact FE follows, the mesh convergence and (``--check``) the drift against the baselines.

Every check is a :class:`Check` with a ``kind`` (``threshold``, ``drift``, ``idealization``, ``convergence``),
a ``status`` (``pass``, ``fail``, ``skipped``; a skipped check says why in ``reason``) and a one-line detail.
:func:`verdict` turns the list into the run's verdict: PASS only when at least one check was evaluated and
none failed. The report, ``verdict.json``, ``junit.xml`` and the terminal all print it
(:mod:`femcheck.verify.render`, :mod:`femcheck.cli.verify`).

A baseline that lacks keys of the configuration being checked is not drift: :func:`require_baseline_keys`
raises :class:`~femcheck.errors.BaselineError` (exit 2), naming the keys and ``--update-baseline``.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.errors import BaselineError
from femcheck.verify.analytical import JOINTS
from femcheck.verify.baseline import compare, load_baseline, save_baseline

#: analytical values may only drift by round-off (the model is closed-form)
ANALYTICAL_RTOL = 1e-9
#: FE values: deterministic structured meshes; direct solvers differ by round-off only (1e-10 seen),
#: so 1e-6 flags any real change of mesh, model or solver while tolerating BLAS/thread differences
FE_RTOL = 1e-6
#: mean relative error analytical vs FE per direction and idealization that a run accepts
ERROR_THRESHOLDS = {"simplified": 0.05, "detailed": 0.10}
#: what a check compares: the analytical-FE error, a baseline, the idealization the contact FE follows, the mesh
CHECK_KINDS = ("threshold", "drift", "idealization", "convergence")
CHECK_STATUSES = ("pass", "fail", "skipped")


@dataclasses.dataclass(frozen=True)
class Check:
    """One check of the run: ``kind`` (:data:`CHECK_KINDS`), ``status`` (:data:`CHECK_STATUSES`), ``detail``
    (what was compared, one line) and, for a skipped check only, ``reason`` (why it was not evaluated)."""

    name: str
    kind: str
    status: str
    detail: str = ""
    reason: str | None = None

    def __post_init__(self):
        if self.kind not in CHECK_KINDS:
            raise ValueError(f"check {self.name!r}: kind {self.kind!r}; expected one of {', '.join(CHECK_KINDS)}")
        if self.status not in CHECK_STATUSES:
            raise ValueError(f"check {self.name!r}: status {self.status!r}; expected one of {', '.join(CHECK_STATUSES)}")
        if (self.status == "skipped") != bool(self.reason):
            raise ValueError(f"check {self.name!r}: a reason is given exactly when the check is skipped")

    def as_json(self) -> dict:
        out = {"name": self.name, "kind": self.kind, "status": self.status, "detail": self.detail}
        if self.reason:
            out["reason"] = self.reason
        return out


def passed_or_failed(name: str, kind: str, ok: bool, detail: str) -> Check:
    return Check(name, kind, "pass" if ok else "fail", detail)


@dataclasses.dataclass(frozen=True)
class Verdict:
    """The verdict of a run: ``passed`` only when at least one check was evaluated and none failed; the names
    of the failed checks; the worst mean analytical-FE error ({table, direction, mean_error_pct,
    threshold_pct}, None without FE)."""

    passed: bool
    failed: tuple[str, ...]
    n_evaluated: int
    n_skipped: int
    worst: dict | None

    @property
    def word(self) -> str:
        return "PASS" if self.passed else "FAIL"

    def line(self) -> str:
        """The one-line verdict: PASS or FAIL, the checks failed, the worst error."""
        if self.n_evaluated == 0:
            head = (f"FAIL: no check was evaluated ({self.n_skipped} skipped), so nothing was verified; an FE "
                    "--level adds the error thresholds, --check the drift against the baselines")
        elif self.failed:
            shown = ", ".join(self.failed[:4]) + (f" and {len(self.failed) - 4} more" if len(self.failed) > 4 else "")
            head = f"FAIL: {len(self.failed)} of {_count(self.n_evaluated)} failed ({shown})"
        else:
            head = f"PASS: {_count(self.n_evaluated)} passed ({self.n_skipped} skipped)"
        if self.worst is None:
            return head + "; worst error: none (no FE level run)"
        w = self.worst
        return (head + f"; worst error: {w['table']} {w['direction']} mean {w['mean_error_pct']:.2f} % "
                f"(threshold {w['threshold_pct']:g} %)")

    def as_json(self) -> dict:
        return {"verdict": self.word, "passed": self.passed, "summary": self.line(), "failed_checks": list(self.failed),
                "evaluated": self.n_evaluated, "skipped": self.n_skipped, "worst_error": self.worst}


def _count(n: int) -> str:
    return f"{n} check" + ("" if n == 1 else "s")


def verdict(checks, worst_errors=()) -> Verdict:
    """The :class:`Verdict` of ``checks``; ``worst_errors``: :func:`femcheck.verify.compute.worst_errors` rows."""
    evaluated = [c for c in checks if c.status != "skipped"]
    failed = tuple(c.name for c in evaluated if c.status == "fail")
    worst = None
    if worst_errors:
        w = dict(worst_errors[0])
        w["threshold_pct"] = 100 * ERROR_THRESHOLDS[w["table"].split("/")[0]]
        worst = w
    return Verdict(passed=bool(evaluated) and not failed, failed=failed, n_evaluated=len(evaluated),
                   n_skipped=len(checks) - len(evaluated), worst=worst)


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
#: (ball in seat, pins in bores) carry only their friction moment (docs/conventions.md §5, "A solid FE model with
#: real ball-in-seat and pin-in-bore contact ... should side with released")
EXPECTED_CONTACT_IDEALIZATION = "released"


def threshold_checks(tables_by_level: dict, expected: str = EXPECTED_CONTACT_IDEALIZATION) -> list[Check]:
    """A ``threshold`` check per (level, joints, direction) mean error against ERROR_THRESHOLDS[level]: the
    matching idealizations, and the contact FE against the ``expected`` idealization (stated before the run,
    not chosen after it); plus one ``idealization`` check that the contact FE follows ``expected``."""
    out = []
    followed = followed_idealization(tables_by_level)
    if followed is not None:
        out.append(passed_or_failed("contact FE follows the expected idealization", "idealization", followed == expected,
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
            out.append(passed_or_failed(f"threshold {name} {k.split()[0]}", "threshold", ok,
                                        f"{name} {k.split()[0]}: mean analytical-FE error {v:.2f} % "
                                        f"{'<=' if ok else '>'} {limit:.0f} %"))
    return out


def threshold_failures(tables_by_level: dict) -> list[str]:
    """Lines for every (level, joints, direction) whose mean error exceeds its threshold."""
    return [c.detail for c in threshold_checks(tables_by_level) if c.status == "fail" and c.kind == "threshold"]


def _key_groups(keys) -> str:
    """Keys ``a/b/.../POINT/DIRECTION/quantity`` summarized by their prefix, with the points they cover."""
    groups: dict[str, set] = {}
    for k in sorted(keys):
        parts = k.split("/")
        groups.setdefault("/".join(parts[:-3]) + "/*/" + parts[-1], set()).add(parts[-3])
    return "; ".join(f"{g} at {', '.join(sorted(p))}" for g, p in groups.items())


def require_baseline_keys(what: str, baseline_path, keys) -> None:
    """Raise :class:`BaselineError` when the baseline file lacks any of ``keys`` (the configuration's)."""
    base = load_baseline(baseline_path)
    if base is None:
        raise BaselineError(f"{what} {baseline_path} not found; create it by running the same verify command "
                            "with --update-baseline")
    missing = sorted(set(keys) - set(base))
    if missing:
        raise BaselineError(f"{what} {baseline_path} lacks {len(missing)} key(s) of this configuration "
                            f"({_key_groups(missing)}); create them by running the same verify "
                            "command with --update-baseline (the FE baseline is merged, its other keys stay)")


def update_baseline_file(name: str, current: dict[str, float], baseline_path) -> None:
    """Write ``current`` as the baseline: the FE file is merged (a subset run adds keys), the analytical
    baseline replaced whole."""
    merged = dict(load_baseline(baseline_path) or {}) if name == "FE drift" else {}
    merged.update(current)
    save_baseline(baseline_path, merged)


def drift_check(name: str, current: dict[str, float], baseline_path, rtol: float, check: bool, update: bool) -> Check:
    """The ``drift`` check of ``current`` against the baseline file (which must hold every key of ``current``:
    :class:`BaselineError` otherwise); skipped, with the reason, without ``--check`` or after an update."""
    if update:
        return Check(name, "drift", "skipped", f"baseline {baseline_path} written", reason="--update-baseline wrote the baseline")
    if not check:
        return Check(name, "drift", "skipped", "drift against the baseline", reason="no --check")
    if baseline_path is None:
        return Check(name, "drift", "skipped", "drift against the baseline", reason="no baseline given")
    require_baseline_keys(name.replace(" drift", " baseline"), baseline_path, current)
    base = load_baseline(baseline_path)
    lines = compare(current, {k: base[k] for k in current}, rtol)
    if lines:
        return Check(name, "drift", "fail", f"{len(lines)} value(s) drifted: " + lines[0] + (" ..." if len(lines) > 1 else ""))
    return Check(name, "drift", "pass", f"{len(current)} values, none drifted by more than {rtol:g} (relative) "
                 f"from {baseline_path}")


def drift_lines(current: dict[str, float], baseline_path, rtol: float) -> list[str]:
    """Every drifted value of ``current`` against the baseline (readable lines; for the report)."""
    base = load_baseline(baseline_path) or {}
    return compare(current, {k: base[k] for k in current if k in base}, rtol)
