"""Solver verification problems (``femcheck check-solver``): one module per problem.

Each module defines ``NAME`` (e.g. ``"cantilever-solid"``) and ``run(mesh: str = "default") -> CheckResult``
where ``mesh`` is ``"coarse" | "default" | "fine"``. The problem compares a computed value with its
closed form (Timoshenko, Johnson, seed 004) and reports the relative error, DOFs, iterations and time.
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

    @property
    def rel_error(self) -> float:
        return abs(self.computed - self.reference) / abs(self.reference)

    def as_json(self) -> dict:
        return {"name": self.name, "quantity": self.quantity, "computed": self.computed, "reference": self.reference,
                "rel_error": self.rel_error, "dofs": self.dofs, "iterations": self.iterations,
                "seconds": self.seconds, "detail": self.detail}


def registry() -> dict[str, object]:
    """{NAME: module} of every verification problem in this package, in name order."""
    from femcheck.registry import plugins
    return dict(sorted((mod.NAME, mod) for mod in plugins(__name__, ("NAME", "run"))))
