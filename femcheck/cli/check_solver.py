"""``femcheck check-solver [NAME …] [--mesh coarse|default|fine] [--json]``: the FE verification suite.

Runs the problems registered in :mod:`femcheck.fe.checks` (all, or those named) and prints, for each,
the computed value, its closed form, the relative error, DOFs, iterations and wall time; ``--json OUT``
writes a list of objects with keys name, computed, reference, rel_error, tolerance, tolerance_reason,
passed, dofs, iterations, seconds ('-': standard output). Exit 1 when a problem is outside its tolerance.
"""
from __future__ import annotations

from typing import List, Optional

import typer
from typer.core import TyperCommand

from femcheck.cli._common import JSON_HELP, emit_json

from femcheck.errors import FemcheckError

MESHES = ("coarse", "default", "fine")


def problems_help() -> str:
    """The list of problems for ``check-solver --help`` (read from the registry when help is asked for)."""
    from femcheck.fe.checks import summaries
    return "Problems (NAME: what it checks):\n\n" + "\n\n".join(f"{n}: {t}" for n, t in summaries().items())


class _ProblemsInHelp(TyperCommand):
    """``--help`` ends with the registered problems; they are looked up only then (importing the problem
    modules costs seconds, which no other command should pay)."""

    def format_help(self, ctx, formatter) -> None:
        self.epilog = problems_help()
        super().format_help(ctx, formatter)


def run_checks(names: list[str] | None = None, mesh: str = "default", progress=None):
    """Run the named checks (all when empty) and return their CheckResults, in registry order;
    ``progress(name)`` after each."""
    from femcheck.fe.checks import registry

    if mesh not in MESHES:
        raise FemcheckError(f"--mesh {mesh!r}: expected one of {', '.join(MESHES)}")
    reg = registry()
    unknown = [n for n in (names or []) if n not in reg]
    if unknown:
        raise FemcheckError(f"unknown check {', '.join(repr(n) for n in unknown)}; available: {', '.join(reg)}")
    from femcheck.fe.checks import run_check
    out = []
    for n in names or list(reg):
        out.append(run_check(reg[n], mesh))
        if progress:
            progress(n)
    return out


def register(app: typer.Typer) -> None:
    @app.command("check-solver", cls=_ProblemsInHelp)
    def check_solver(
        names: Optional[List[str]] = typer.Argument(None, help="problems to run (default: all)"),
        mesh: str = typer.Option("default", "--mesh", help="refinement: coarse | default | fine"),
        json_out: Optional[str] = typer.Option(None, "--json", metavar="OUT", help=JSON_HELP),
    ) -> None:
        """Verify the FE solver against closed forms (Timoshenko, Johnson, seed 004): each problem's computed
        value, its closed form, the relative error against the problem's tolerance, DOFs and wall time."""
        from femcheck.cli import progress
        from femcheck.fe.checks import expected_seconds, registry
        chosen = list(names or []) or list(registry())
        with progress("check-solver", None, weights=[expected_seconds(n, mesh) for n in chosen],
                      stderr=json_out == "-") as bar:
            results = run_checks(list(names or []), mesh, progress=lambda n: bar.advance(1, n))
        if json_out:
            keys = ("name", "computed", "reference", "rel_error", "tolerance", "tolerance_reason", "passed", "dofs",
                    "iterations", "seconds")
            emit_json([{k: r.as_json()[k] for k in keys} | {"quantity": r.quantity, "detail": r.detail} for r in results],
                      json_out)
        else:
            from rich.console import Console
            from rich.table import Table

            table = Table(title=f"femcheck check-solver (mesh: {mesh})")
            for col in ("problem", "quantity", "computed", "closed form", "rel. error", "tolerance", "result", "DOFs",
                        "iterations", "wall s"):
                table.add_column(col, justify="left" if col in ("problem", "quantity", "result") else "right")
            for r in results:
                table.add_row(r.name, r.quantity, f"{r.computed:.6g}", f"{r.reference:.6g}", f"{r.rel_error:.2e}",
                              f"{r.tolerance:.0e}", "pass" if r.passed else "[red]FAIL[/]", str(r.dofs), str(r.iterations),
                              f"{r.seconds:.2f}")
            Console(width=160).print(table)
            for r in results:
                print(f"  {r.name}: tolerance {r.tolerance:.0e} - {r.tolerance_reason}")
        failed = [r.name for r in results if not r.passed]
        if failed:
            typer.secho(f"check-solver: {len(failed)} of {len(results)} problem(s) outside tolerance: {', '.join(failed)}",
                        err=True, fg="red")
            raise typer.Exit(1)
