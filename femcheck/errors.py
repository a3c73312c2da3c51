"""femcheck's own exception types.

Every message says what was found, what was expected and, where it helps, a hint
(meshio / Pinocchio style), so that a user can fix the input without reading code.
"""
from __future__ import annotations


class FemcheckError(Exception):
    """Base class of all femcheck errors. The CLI prints the message on one line and exits with ``exit_code``
    (2: bad input, the default)."""

    exit_code = 2


class CheckFailedError(FemcheckError):
    """A run that completed but whose check failed (too many failed samples, a gated verdict): exit 1."""

    exit_code = 1


class CaseError(FemcheckError, ValueError):
    """An invalid case file. The message names the file and the dotted key.

    Example: ``cases/x.toml: proximal_link.outer_diameter_m = -0.006; expected > 0``.
    """

    def __init__(self, path, key: str, message: str):
        self.path = str(path)
        self.key = key
        super().__init__(f"{self.path}: {key}: {message}" if key else f"{self.path}: {message}")


class UnreachablePoseError(FemcheckError, ValueError):
    """A TCP pose that the mechanism cannot reach; names the pose and the chain (leg)."""

    def __init__(self, pose_label: str, chain: int, reason: str):
        self.pose_label = pose_label
        self.chain = chain
        super().__init__(f"pose {pose_label} is unreachable by chain (leg) {chain}: {reason}")


class ConvergenceError(FemcheckError, RuntimeError):
    """A nonlinear solve that did not converge; carries its residual history."""

    def __init__(self, message: str, residual_history=(), detail: dict | None = None):
        self.residual_history = list(residual_history)
        self.detail = dict(detail or {})
        hist = ", ".join(f"{r:.3e}" for r in self.residual_history[-12:])
        super().__init__(f"{message}; residual history (last {min(12, len(self.residual_history))}): [{hist}]")


class MeasuredDataError(FemcheckError, ValueError):
    """Invalid measured-data CSV; names the file, the row (1-based, header = row 1) and the column."""

    def __init__(self, path, row: int | None, column: str | None, message: str):
        self.path, self.row, self.column = str(path), row, column
        where = f"{self.path}"
        if row is not None:
            where += f", row {row}"
        if column is not None:
            where += f", column '{column}'"
        super().__init__(f"{where}: {message}")


class SingularPoseError(FemcheckError, ValueError):
    """A pose at or too near a singularity of the mechanism: names the pose, the leg and cond(J_h)."""

    def __init__(self, pose_label: str, leg: int, condition: float, limit: float, detail: str = ""):
        self.pose_label, self.leg, self.condition, self.limit = pose_label, leg, condition, limit
        cond = "inf" if not condition < float("inf") else f"{condition:.4g}"
        super().__init__(f"pose {pose_label} is singular or too near a singularity: cond(J_h) = {cond} > {limit:g} "
                         f"(leg {leg}{': ' + detail if detail else ''}); move away from it or raise --max-condition")


class BaselineError(FemcheckError):
    """A regression baseline that is missing or lacks keys of the configuration being checked: bad input (exit 2),
    never drift. The message names the file, the keys and how to make them (``--update-baseline``)."""
