"""``femcheck check-joints CASE [--joint spherical|universal|all] [--mesh coarse|default|fine] [--point P0]
[--json OUT] [--csv OUT]``: contact FE of the passive joints vs their closed-form laws.

Each joint is meshed and solved with penalty contact, augmented Lagrangian and modified Newton–Raphson,
condensed onto its contact DOFs (:mod:`femcheck.fe_device.joint_fe`), under the eq. 1 force levels of
the most loaded joint at the test point (:mod:`femcheck.fe_device.joint_check`). JSON (``-`` = stdout):
a list with one object per joint, keys ``converged``, ``dofs``, ``iterations``, ``seconds``,
``fe_compliance``, ``analytical_compliance`` (6 x 6, SI) and ``error_pct`` (per component), and more.
``--csv`` writes the joint table. The terminal table gives each compliance with its unit (m/N, rad/(N m)), and
a last line gives the verdict: which closed-form laws are within 10 % of the contact FE. Progress (with an ETA
weighted by the joints' expected costs) goes to the terminal, or to plain lines off a terminal.
Exit 0 when every joint converged; a joint that does not converge
raises ConvergenceError (residual history, chattering points) and exits 1.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer


def register(app: typer.Typer) -> None:
    @app.command("check-joints")
    def check_joints(
        case_path: Path = typer.Argument(..., help="case TOML"),
        joint: str = typer.Option("all", "--joint", help="spherical | universal | all"),
        mesh: str = typer.Option("default", "--mesh", help="coarse | default | fine"),
        point: str = typer.Option("P0", "--point", help="test point P0..P8 whose load the joints carry"),
        json_out: Optional[str] = typer.Option(None, "--json", help="write JSON to this path ('-' = stdout)"),
        csv_out: Optional[Path] = typer.Option(None, "--csv", help="write the joint table CSV to this path"),
        extended_case: Optional[Path] = typer.Option(None, "--extended-case", help="write a copy of CASE whose "
                                                     "[model.law_scale] puts the FE-measured joint laws into the "
                                                     "analytical model (for diagnose, sweep, map, stiffness)"),
    ) -> None:
        """Contact FE of each passive joint under the device load vs the closed-form joint laws."""
        from femcheck.case import load_case
        from femcheck.errors import ConvergenceError, FemcheckError
        from femcheck.fe_device.joint_check import check_joint, joint_table_rows, write_joint_table_csv
        from femcheck.fe_device.joint_fe import COMPONENTS, JOINTS
        from femcheck.report.atomic import write_text_atomic

        if joint not in JOINTS + ("all",):
            raise FemcheckError(f"--joint {joint!r}: expected one of {', '.join(JOINTS)}, all")
        from femcheck.report.atomic import refuse_input_overwrite
        for out in (json_out if json_out not in (None, "-") else None, csv_out, extended_case):
            if out:
                refuse_input_overwrite(out, [case_path])
        case = load_case(case_path)
        if extended_case:
            import tomllib
            if joint != "all":
                raise FemcheckError("--extended-case needs both joints: use --joint all")
            if "law_scale" in tomllib.loads(Path(case_path).read_text()).get("model", {}):
                raise FemcheckError(f"{case_path}: [model.law_scale] is already set; --extended-case expects a case "
                                    "without it")
        names = JOINTS if joint == "all" else (joint,)
        results = []
        from femcheck.cli import console, progress
        from femcheck.fe_device.joint_check import progress_weights
        try:
            with progress("joint contact FE", None, weights=progress_weights(names), stderr=json_out == "-") as bar:
                for name in names:
                    results.append(check_joint(case, name, mesh, point, progress=lambda d: bar.advance(1, d)))
        except ConvergenceError as exc:
            typer.secho(f"check failed: {exc}", err=True, fg="red")
            raise typer.Exit(1)
        text = json.dumps(results, indent=2)
        if json_out == "-":
            typer.echo(text)
        elif json_out:
            write_text_atomic(json_out, text + "\n")
        if csv_out:
            write_text_atomic(csv_out, write_joint_table_csv(joint_table_rows(results)))
        if extended_case:
            from femcheck.fe_device.joint_check import extended_case_text
            write_text_atomic(extended_case, extended_case_text(Path(case_path).read_text(), str(case_path), results))
        if json_out == "-":
            return
        from rich.table import Table

        from femcheck.fe_device.joint_check import verdict_line
        t = Table(title=f"femcheck check-joints {case_path} (mesh {mesh}, point {point.upper()}): compliance of each "
                        "component with the other five held")
        for col in ("joint", "component", "unit", "FE", "analytical", "error %", "DOFs", "iterations", "wall s"):
            t.add_column(col, justify="left" if col in ("joint", "component", "unit") else "right")
        for r in results:
            for k, comp in enumerate(COMPONENTS):
                fe, an, e = r["fe_component_compliance"][k], r["analytical_compliance"][k][k], r["error_pct"][comp]
                t.add_row(r["joint"], comp, "m/N" if comp.startswith("u_") else "rad/(N m)",
                          "inf (free)" if fe is None else f"{fe:.4g}", f"{an:.4g}",
                          "-" if e is None else f"{e:+.1f}", str(r["dofs"]), str(r["iterations"]), f"{r['seconds']:.1f}")
        con = console()
        con.print(t)
        con.print("error % = 100 (FE - analytical) / analytical; '-': no percentage where the FE leaves the component "
                  "free (a mechanism)")
        con.print(verdict_line(joint_table_rows(results)))
