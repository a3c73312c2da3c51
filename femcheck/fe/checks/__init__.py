"""Solver verification problems (``femcheck check-solver``): one module per problem.

Each module defines ``NAME`` (e.g. ``"cantilever-solid"``), ``run(mesh: str = "default") -> CheckResult``
where ``mesh`` is ``"coarse" | "default" | "fine"``, and ``TOLERANCE`` ({mesh: relative error}) with a
one-line ``TOLERANCE_REASON``. The problem compares a computed value with its closed form (Timoshenko,
Johnson, seed 004) and reports the relative error, DOFs, iterations and time; :func:`run_check` attaches
the tolerance, so ``passed`` is decided in one place.
"""
from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True)
class CheckResult:
    """Outcome of one verification problem (SI units; ``quantity`` says what ``computed`` is)."""

    name: str
    quantity: str
    computed: float
    reference: float
    dofs: int
    iterations: int
    seconds: float
    detail: dict = dataclasses.field(default_factory=dict)
    tolerance: float = float("nan")
    tolerance_reason: str = ""

    @property
    def rel_error(self) -> float:
        return abs(self.computed - self.reference) / abs(self.reference)

    @property
    def passed(self) -> bool:
        """Whether the relative error is within the tolerance (False when no tolerance is attached, or NaN)."""
        return bool(self.rel_error <= self.tolerance)

    def as_json(self) -> dict:
        return {"name": self.name, "quantity": self.quantity, "computed": self.computed, "reference": self.reference,
                "rel_error": self.rel_error, "tolerance": self.tolerance, "tolerance_reason": self.tolerance_reason,
                "passed": self.passed, "dofs": self.dofs, "iterations": self.iterations,
                "seconds": self.seconds, "detail": self.detail}


def run_check(module, mesh: str = "default") -> CheckResult:
    """Run one problem module at ``mesh`` and attach its tolerance and reason."""
    result = module.run(mesh)
    return dataclasses.replace(result, tolerance=float(module.TOLERANCE[mesh]), tolerance_reason=module.TOLERANCE_REASON)


def registry() -> dict[str, object]:
    """{NAME: module} of every verification problem in this package, in name order."""
    from femcheck.registry import plugins
    return dict(sorted((mod.NAME, mod) for mod in plugins(__name__, ("NAME", "run"))))


def summaries() -> dict[str, str]:
    """{NAME: one line on what the problem checks}, from the first line of each module's docstring."""
    out = {}
    for name, mod in registry().items():
        line = (mod.__doc__ or "").strip().splitlines()[0] if mod.__doc__ else ""
        out[name] = line.split(":", 1)[1].strip() if line.startswith(f"``{name}``:") else line
    return out


#: wall time of each problem at the default mesh (s; ``femcheck check-solver --json``, the shared 2-core machine
#: under load), the expected cost behind the progress ETA; other meshes scale all problems alike
EXPECTED_S = {"bar-modal": 0.44, "cantilever-beam": 5.2, "cantilever-solid": 4.9, "contact-patch": 6.2,
              "friction-block": 38.3, "hertz-cylinder": 23.2, "hertz-sphere": 284.6}


def expected_seconds(name: str, mesh: str = "default") -> float:
    """Expected relative cost of problem ``name`` (:data:`EXPECTED_S`; 10 s for a problem without a record)."""
    return EXPECTED_S.get(name, 10.0)
