"""``femcheck check-solver [NAME …] [--mesh coarse|default|fine] [--json]``: the FE verification suite.

Runs the problems registered in :mod:`femcheck.fe.checks` (all, or those named) and prints, for each,
the computed value, its closed form, the relative error, DOFs, iterations and wall time; ``--json``
prints a list of objects with keys name, computed, reference, rel_error, dofs, iterations, seconds.
"""
from __future__ import annotations

import json
from typing import List, Optional

import typer

from femcheck.errors import FemcheckError

MESHES = ("coarse", "default", "fine")


def run_checks(names: list[str] | None = None, mesh: str = "default"):
    """Run the named checks (all when empty) and return their CheckResults, in registry order."""
    from femcheck.fe.checks import registry

    if mesh not in MESHES:
        raise FemcheckError(f"--mesh {mesh!r}: expected one of {', '.join(MESHES)}")
    reg = registry()
    unknown = [n for n in (names or []) if n not in reg]
    if unknown:
        raise FemcheckError(f"unknown check {', '.join(repr(n) for n in unknown)}; available: {', '.join(reg)}")
    return [reg[n].run(mesh) for n in (names or list(reg))]


def register(app: typer.Typer) -> None:
    @app.command("check-solver")
    def check_solver(
        names: Optional[List[str]] = typer.Argument(None, help="problems to run (default: all)"),
        mesh: str = typer.Option("default", "--mesh", help="refinement: coarse | default | fine"),
        as_json: bool = typer.Option(False, "--json", help="print a JSON list instead of a table"),
    ) -> None:
        """Verify the FE solver against closed forms (Timoshenko, Johnson, seed 004)."""
        results = run_checks(list(names or []), mesh)
        if as_json:
            keys = ("name", "computed", "reference", "rel_error", "dofs", "iterations", "seconds")
            typer.echo(json.dumps([{k: r.as_json()[k] for k in keys} | {"quantity": r.quantity, "detail": r.detail}
                                   for r in results], indent=2, default=float))
            return
        from rich.console import Console
        from rich.table import Table

        table = Table(title=f"femcheck check-solver (mesh: {mesh})")
        for col in ("problem", "quantity", "computed", "closed form", "rel. error", "DOFs", "iterations", "wall s"):
            table.add_column(col, justify="left" if col in ("problem", "quantity") else "right")
        for r in results:
            table.add_row(r.name, r.quantity, f"{r.computed:.6g}", f"{r.reference:.6g}", f"{r.rel_error:.2e}",
                          str(r.dofs), str(r.iterations), f"{r.seconds:.2f}")
        Console(width=140).print(table)
