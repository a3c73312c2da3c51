"""The ``[solver]`` table of a case file: which sparse direct solver factorizes the FE systems.

    [solver]
    linear = "cholmod"   # "auto" | "pardiso" | "cholmod" | "mumps" | "superlu"

``auto`` = PARDISO where MKL exists, else CHOLMOD for symmetric positive definite systems and UMFPACK LU for
unsymmetric ones (frictional contact tangents), else SuperLU with a warning; see
:mod:`femcheck.fe.linear_solver`. The CLI option ``femcheck --linear-solver NAME`` and the environment
variable ``FEMCHECK_LINEAR_SOLVER`` override the case file (command line beats file beats environment).
"""
from __future__ import annotations

import dataclasses
from typing import Literal

from femcheck.case.schema import option

LinearSolver = Literal["auto", "pardiso", "cholmod", "mumps", "superlu"]


@dataclasses.dataclass(frozen=True)
class SolverOptions:
    """``[solver]``: ``linear`` names the sparse direct solver (see module docstring)."""

    linear: LinearSolver = option("auto", doc="sparse direct solver: auto | pardiso | cholmod | mumps | superlu")


def apply(case, cli_choice: str | None = None) -> str:
    """Make the case's ``[solver] linear`` the process-wide choice unless the command line (or an earlier
    ``--linear-solver``) already set one; returns the choice in force ("auto" or a solver name)."""
    from femcheck.fe import linear_solver as ls
    if cli_choice is not None:
        ls.set_preferred(cli_choice)
    elif ls._preferred is None:
        linear = getattr(getattr(case, "solver", None), "linear", "auto")
        if linear != "auto":
            ls.set_preferred(linear)
    return ls.preferred()
