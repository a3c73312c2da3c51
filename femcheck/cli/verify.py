"""``femcheck verify``: the main job — models across the test-point cube, tables, plots, drift check."""
from __future__ import annotations

from pathlib import Path

import typer

from femcheck.case import load_case
from femcheck.kinematics.psu6 import POINT_LABELS


def register(app: typer.Typer) -> None:
    @app.command("verify")
    def verify_cmd(
        case_path: str = typer.Argument(..., metavar="CASE", help="case file (TOML)"),
        points: str = typer.Option(None, "--points", help="comma-separated subset of P0..P8 (default: all)"),
        out: Path = typer.Option(Path("reports/verify"), "--out", help="run folder for tables, plots, report.html, manifest.json"),
        check: bool = typer.Option(False, "--check", help="compare with the committed baseline; exit 1 on drift"),
        baseline: Path = typer.Option(Path("reports/baseline/analytical.json"), "--baseline", help="baseline file for --check"),
        update_baseline: bool = typer.Option(False, "--update-baseline", help="write the current values as the baseline"),
    ):
        """Verify the analytical models on the test cube and write relative-error tables (seed 000 Tables 2-3).

        Writes CSV/Markdown tables, deflection and contribution plots, a self-contained report.html and
        manifest.json into --out. (The FE comparison, errors_simplified.csv / errors_detailed.csv,
        is added by the FE verification.)
        """
        from femcheck.cli import console
        from femcheck.verify.run import error_rows, run_verify
        case = load_case(case_path)
        pts = None
        if points:
            pts = [p.strip().upper() for p in points.split(",") if p.strip()]
            bad = [p for p in pts if p not in POINT_LABELS]
            if bad:
                raise typer.BadParameter(f"--points: {bad[0]!r}; expected P0..P8")
        run = run_verify(case, out, pts, check=check, baseline_path=baseline if (check or update_baseline) else None,
                         update_baseline=update_baseline, command="femcheck verify " + case_path)
        con = console()
        from rich.table import Table
        for joints in ("rigid", "released"):
            rows = error_rows(run.analytical, joints)
            t = Table(title=f"simplified vs detailed analytical model, {joints} joints (relative error %)")
            for c in rows[0]:
                t.add_column(c, justify="right")
            for r in rows:
                t.add_row(*[f"{v:.1f}" if isinstance(v, float) else str(v) for v in r.values()])
            con.print(t)
        con.print(f"wrote {len(run.files) + 1} files to {out} in {run.seconds:.2f} s (report: {out / 'report.html'})")
        if update_baseline:
            con.print(f"baseline written: {baseline}")
        if check:
            if run.drift:
                con.print(f"[red]drift against {baseline}:[/]")
                for line in run.drift:
                    con.print("  " + line)
                raise typer.Exit(1)
            con.print(f"[green]no drift against {baseline}[/]")
