"""``femcheck verify``: the main job — analytical and FE models across the test-point cube, relative-error
tables, plots, VTU, drift and threshold check."""
from __future__ import annotations

import os
from pathlib import Path

import typer

from femcheck.cli._common import load_case_for
from femcheck.report.atomic import check_output_file
from femcheck.report.run_folder import prepare_run_folder

from femcheck.kinematics.psu6 import POINT_LABELS

LEVEL_CHOICES = {"simplified": ("simplified",), "detailed": ("detailed",), "both": ("simplified", "detailed"),
                 "none": ()}


def register(app: typer.Typer) -> None:
    @app.command("verify")
    def verify_cmd(
        case_path: str = typer.Argument(..., metavar="CASE", help="case file (TOML)"),
        level: str = typer.Option("both", "--level", help="FE levels: simplified | detailed | both | none (analytical only)"),
        points: str = typer.Option(None, "--points", help="comma-separated subset of P0..P8 (default: all)"),
        mesh: str = typer.Option("default", "--mesh", help="FE mesh: coarse | default | fine"),
        jobs: int = typer.Option(min(os.cpu_count() or 1, 4), "--jobs", min=1, help="worker processes for the FE solves (default: CPUs, at most 4)"),
        out: Path = typer.Option(Path("reports/verify"), "--out", help="run folder for tables, plots, report.html, manifest.json"),
        check: bool = typer.Option(False, "--check", help="add the drift checks against the committed baselines (the error "
                                   "thresholds, idealization and convergence checks always run; any failed check exits 1)"),
        baseline: Path = typer.Option(Path("reports/baseline/analytical.json"), "--baseline", help="analytical baseline for --check"),
        fe_baseline: Path = typer.Option(None, "--fe-baseline", help="FE baseline (default reports/baseline/fe_<mesh>.json)"),
        update_baseline: bool = typer.Option(False, "--update-baseline", help="write the current values as the baseline(s)"),
        vtu: str = typer.Option("first", "--vtu", help="VTU of the deformed FE models (zlib-compressed): first = at "
                                "the first point (about 40 MB at the default mesh), all = at every point, none"),
        no_vtu: bool = typer.Option(False, "--no-vtu", help="same as --vtu none"),
        convergence: str = typer.Option(None, "--convergence", help="mesh-convergence study (coarse/default/fine) at this point, "
                                        "e.g. P0; default: P0 for a full default-mesh run, else none ('none' to skip)"),
        force: bool = typer.Option(False, "--force", help="empty --out even if it holds files femcheck did not write"),
        joint_fe: bool = typer.Option(True, "--joint-fe/--no-joint-fe", help="detailed level: measure both passive "
                                      "joints by their contact FE (force ladder, cached) and use those laws in the "
                                      "device FE, run the ball tilt contact FE for the slip moment and the joint table "
                                      "(first run about 2-4 min); off: the closed-form joint laws on the FE side too"),
        joint_mesh: str = typer.Option("coarse", "--joint-mesh", help="mesh of the joint contact FE: coarse | default | fine"),
    ):
        """Verify the analytical models against the device FE model on the test cube (seed 000 §4.2, §4.5).

        A parallel_device case (docs/parallel_device.md) is verified against the FE of its description with solid
        links (--mesh; the detailed level with the drives' elements and, --joint-fe, the joints' contact FE) and with
        beam links (the analytical laws: the chain algebra): errors_<level>[_beam].csv/.md in --out; --jobs, --vtu
        and the baselines do not apply.

        Writes errors_simplified.csv / errors_detailed.csv (point, direction, joints, analytical_mm, fe_mm,
        rel_error_pct (%); the detailed file compares the contact-joint FE with both idealizations, and
        errors_detailed_matched.csv the FE with the same idealization), Markdown/HTML tables in the layout of seed 000 Tables 2-3, deflection and contribution
        plots, VTU of the first point (--vtu all: every point), report.html and manifest.json into --out.
        """
        from femcheck.cli import console
        from femcheck.fe_device.mesh_levels import MESH_LEVELS
        from femcheck.verify.run import error_rows, error_table, fe_error_rows, has_contact_joints, run_verify
        from femcheck.verify.run import VTU_CHOICES
        if vtu not in VTU_CHOICES:
            raise typer.BadParameter(f"--vtu: {vtu!r}; expected one of {', '.join(VTU_CHOICES)}")
        vtu = "none" if no_vtu else vtu
        if level not in LEVEL_CHOICES:
            raise typer.BadParameter(f"--level: {level!r}; expected one of {', '.join(LEVEL_CHOICES)}")
        if mesh not in MESH_LEVELS:
            raise typer.BadParameter(f"--mesh: {mesh!r}; expected one of {', '.join(MESH_LEVELS)}")
        if joint_mesh not in MESH_LEVELS:
            raise typer.BadParameter(f"--joint-mesh: {joint_mesh!r}; expected one of {', '.join(MESH_LEVELS)}")
        case = load_case_for(case_path, "verify", kinds=("haptic_6psu", "parallel_device"))
        if case.kind == "parallel_device":
            from femcheck.cli._parallel_device import verify
            return verify(case, case_path, levels=LEVEL_CHOICES[level], points=points, out=out, force=force, check=check,
                          mesh=mesh, joint_fe=joint_fe, joint_mesh=joint_mesh)
        pts = None
        if points:
            pts = [p.strip().upper() for p in points.split(",") if p.strip()]
            bad = [p for p in pts if p not in POINT_LABELS]
            if bad:
                raise typer.BadParameter(f"--points: {bad[0]!r}; expected P0..P8")
        levels = LEVEL_CHOICES[level]
        if convergence is None:
            convergence = "P0" if (levels and mesh == "default" and pts is None) else "none"
        conv_point = None if convergence.lower() == "none" else convergence.upper()
        if conv_point is not None and conv_point not in POINT_LABELS:
            raise typer.BadParameter(f"--convergence: {convergence!r}; expected P0..P8 or none")
        fe_base = fe_baseline or Path(f"reports/baseline/fe_{mesh}.json")
        for opt, path in (("--baseline", baseline), ("--fe-baseline", fe_base if levels else None)):
            if path is not None and (check and not update_baseline) and not Path(path).is_file():
                raise typer.BadParameter(f"{opt}: {str(path)!r} not found; expected a baseline JSON (or run --update-baseline)")
        if update_baseline:
            check_output_file(baseline, "--baseline")
            if levels:
                check_output_file(fe_base, "--fe-baseline")
        prepare_run_folder(out, "femcheck verify", force=force, inputs=[case_path, baseline, fe_base])
        con = console()
        from femcheck.cli import progress
        from femcheck.verify.progress_plan import plan
        # each step's expected cost (cold, or read from the caches), so that the ETA counts work, not steps
        work = plan(case, pts or POINT_LABELS, levels, mesh, joint_fe, joint_mesh, conv_point)
        # progress goes to stderr: stdout opens and closes with the verdict
        err = console(stderr=True)
        with progress("verify", None, err, weights=work.weights) as bar:
            run = run_verify(case, out, pts, check=check, baseline_path=baseline if (check or update_baseline) else None,
                             update_baseline=update_baseline, command="femcheck verify " + case_path, levels=levels,
                             mesh=mesh, jobs=jobs, progress=lambda desc: bar.advance(1, desc, work=work(desc)),
                             fe_baseline_path=fe_base if (check or update_baseline) else None, vtu=vtu,
                             convergence_point=conv_point, joint_fe=joint_fe, joint_mesh=joint_mesh)
        print_run(con, run, mesh, baseline if update_baseline else None, fe_base if update_baseline and levels else None)
        if not run.verdict.passed:
            raise typer.Exit(1)


#: the title suffix of a table that no check reads
INFORMATIONAL = "informational, not a check"


def print_run(con, run, mesh: str, baseline_written=None, fe_baseline_written=None) -> None:
    """The terminal view of a finished run: the verdict line first, the tables (each marked as checked, with its
    threshold, or informational), the failed checks and drifted values, the files, the verdict line last."""
    from rich.table import Table

    from femcheck.verify.check import ERROR_THRESHOLDS, EXPECTED_CONTACT_IDEALIZATION
    from femcheck.verify.run import error_rows, error_table, fe_error_rows, has_contact_joints
    v = run.verdict
    style = "bold green" if v.passed else "bold red"

    def say_verdict():
        con.print(v.line(), style=style, markup=False, highlight=False)

    def show(title, rows):
        t = Table(title=title)
        for c in rows[0]:
            t.add_column(c, justify="right")
        for r in rows:
            t.add_row(*[f"{x:.2f}" if isinstance(x, float) else str(x) for x in r.values()])
        con.print(t)
    say_verdict()
    for joints in ("rigid", "released"):
        show(f"simplified vs detailed analytical model, {joints} joints (relative error %) — {INFORMATIONAL}",
             error_rows(run.analytical, joints))
    if run.fe is not None:
        for lvl in run.fe.levels:
            limit = f"checked: mean per direction <= {100 * ERROR_THRESHOLDS[lvl]:g} %"
            variants = ["contact", None] if lvl == "detailed" and has_contact_joints(run.fe) else [None]
            for fe_joints in variants:
                rows = fe_error_rows(run.analytical, run.fe, lvl, fe_joints)
                for joints in ("rigid", "released"):
                    what = f"{joints} joints" if fe_joints is None else f"{joints} analytical vs contact-joint FE"
                    role = limit if fe_joints is None or joints == EXPECTED_CONTACT_IDEALIZATION else INFORMATIONAL
                    show(f"{lvl} analytical vs {lvl} FE, {what} (relative error %, mesh {mesh}) — {role}",
                         error_table(rows, joints, run.fe.directions))
        ts = run.fe.timings_s
        con.print(f"FE: meshing {ts['meshing']:.1f} s, assembly {ts['assembly']:.1f} s, solve {ts['solve']:.1f} s "
                  f"(summed over solves), platform/loads {ts['platform']:.1f} s, wall {ts['wall']:.1f} s")
    con.print(f"wrote {len(run.files) + 1} files to {run.out_dir} in {run.seconds:.2f} s (report: "
              f"{run.out_dir / 'report.html'})", markup=False, highlight=False)
    if baseline_written is not None:
        con.print(f"baseline written: {baseline_written}" + (f", {fe_baseline_written}" if fe_baseline_written else ""),
                  markup=False, highlight=False)
    failed = [c for c in run.checks if c.status == "fail"]
    if failed:
        con.print("failed checks:", style="red")
        for c in failed:
            con.print(f"  [{c.kind}] {c.name}: {c.detail}", markup=False, highlight=False)
    if run.drift:
        con.print("drifted values:", style="red")
        for line in run.drift:
            con.print("  " + line, markup=False, highlight=False)
    say_verdict()
