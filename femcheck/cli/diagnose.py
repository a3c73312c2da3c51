"""``femcheck diagnose CASE MEASURED.csv``: where the model is wrong, the physical cause, the extended model
and its held-out gain (docs/diagnose.md)."""
from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.markup import escape
from rich.table import Table

from femcheck.cli import console
from femcheck.cli._common import Joints, ModelLevel, load_case_for


def register(app: typer.Typer) -> None:
    @app.command("diagnose")
    def diagnose_cmd(
        case_path: str = typer.Argument(..., metavar="CASE", help="case file (TOML), e.g. cases/haptic_6psu.toml"),
        measured: str = typer.Argument(..., metavar="MEASURED.csv", help="measured-data CSV (docs/diagnose.md)"),
        model: ModelLevel = typer.Option(ModelLevel.detailed, "--model", help="analytical model to check"),
        joints: Joints = typer.Option(None, "--joints", help="joint idealization; default: the case's [model] joint_rotations"),
        json_out: str = typer.Option(None, "--json", help="write the diagnosis as JSON to this file ('-': standard output)"),
        report: str = typer.Option(None, "--report", help="write report.md, report.html and plots into this folder"),
        max_effects: int = typer.Option(2, "--max-effects", min=1, max=3, help="most effects greedy selection may name"),
        sigma_mm: float = typer.Option(None, "--sigma-mm", help="serial robots: noise of one marker coordinate (1 sigma, mm); "
                                       "default: the case's measurement.sigma_m, else repeated poses"),
        folds: int = typer.Option(None, "--folds", min=2, help="serial robots: K of the K-fold cross-validation "
                                  "(default: the case's measurement.folds; the CSV's fold column wins)"),
        pose_table: str = typer.Option(None, "--pose-table", metavar="PLAN.json",
                                  help="pose table for point ids other than P0..P8: the JSON of `femcheck plan`"),
        evidence: str = typer.Option(None, "--evidence", metavar="bic|laplace",
                                     help="evidence approximation of the posterior probabilities (default bic; "
                                          "docs/diagnose.md, calibration)"),
        likelihood: str = typer.Option(None, "--likelihood", metavar="gauss|student",
                                       help="likelihood of the evidence: gauss (sigma known) or student (sigma's "
                                            "uncertainty from the trial scatter integrated out; default gauss; "
                                            "docs/diagnose.md)"),
        extended_case: str = typer.Option(None, "--extended-case", metavar="OUT.toml",
                                          help="write a copy of CASE with the named explanation as case keys, each "
                                               "with its 95 % interval and the cause that set it"),
        compensation: str = typer.Option(None, "--compensation", metavar="OUT.csv",
                                         help="serial trees: predicted elastic deflection of each marker (mm) at the "
                                              "joint angles of --poses, by the extended model"),
        poses: str = typer.Option(None, "--poses", metavar="POSES.csv",
                                  help="joint angles of the compensation table (columns q1_rad..qN_rad, optional "
                                       "pose and payload_kg)"),
        force: bool = typer.Option(False, "--force", help="diagnose readings even when their median deflection is "
                                   "more than 10x off the case's prediction (a unit slip, by default exit 2)"),
    ):
        """Residuals of the model against measured deflections, the physical causes (effect library), the
        fitted extension and the held-out error before/after (leave-points-out cross-validation)."""
        from femcheck.diagnose import AnalyticalChainModel, diagnose
        from femcheck.measured import process, read_measured_csv
        from femcheck.diagnose.device_match import device_mismatch_warnings
        from femcheck.report.atomic import check_output_dir, check_output_file, refuse_input_overwrite, write_text_atomic

        from femcheck.diagnose.evidence import EVIDENCE_METHODS
        if evidence is not None and evidence not in EVIDENCE_METHODS:
            raise typer.BadParameter(f"--evidence: {evidence!r}; expected one of {', '.join(EVIDENCE_METHODS)}")
        from femcheck.diagnose.evidence import LIKELIHOODS
        if likelihood is not None and likelihood not in LIKELIHOODS:
            raise typer.BadParameter(f"--likelihood: {likelihood!r}; expected one of {', '.join(LIKELIHOODS)}")
        if json_out and json_out != "-":
            check_output_file(json_out, "--json")
        if report:
            check_output_dir(report, "--report")
        case = load_case_for(case_path, "diagnose", kinds=("haptic_6psu", "serial_tree", "serial_robot", "parallel_device"))
        from femcheck.cli._extended_case import check_extended_outputs
        check_extended_outputs(case, case_path, measured, extended_case, compensation, poses)
        from femcheck.case.plausibility import dimension_warnings
        dim_warnings = dimension_warnings(case)
        for w in dim_warnings:   # first: a unit slip in the case colours every line after it (stderr keeps --json - clean)
            typer.echo(f"warning: {w}", err=True)
        if case.meta.kind in ("serial_tree", "serial_robot"):
            return _diagnose_serial(case, case_path, measured, json_out, report, sigma_mm, folds,
                                    extended_case, compensation, poses)
        if case.kind == "parallel_device":
            from femcheck.cli._parallel_device import diagnose as diagnose_parallel
            return diagnose_parallel(case, case_path, measured, model=model.value,
                                     joints=joints.value if joints else None, json_out=json_out, force=force,
                                     warnings=dim_warnings, extended_case=extended_case)
        for out in ((json_out,) if json_out != "-" else ()) + \
                ((str(Path(report) / "report.md"), str(Path(report) / "report.html")) if report else ()):
            if out:
                refuse_input_overwrite(out, [case_path, measured])
        data = read_measured_csv(measured)
        table = None
        if pose_table:
            from femcheck.diagnose.plan import read_pose_table
            table = read_pose_table(pose_table, case)
        readings = process(data, case, table)
        m = AnalyticalChainModel(case, model.value, joints.value if joints else case.model.joint_rotations)
        if not force:
            _refuse_implausible_scale(m, readings, measured)
        mismatch = dim_warnings + device_mismatch_warnings(case, data.meta, readings, m)
        from femcheck.cli import progress
        with progress("diagnose", None, stderr=json_out == "-") as bar:
            d = diagnose(m, readings, max_effects=max_effects, evidence_method=evidence, likelihood=likelihood,
                         progress=bar)
        result = {"case": case.source, "case_sha256": case.sha256, "measured": str(measured), **d.as_json()}
        result["warnings"] = list(result.get("warnings", [])) + mismatch
        if extended_case:      # refused causes stop here (exit 2), before anything is written
            from femcheck.diagnose.extended_case import extended_case_text
            text = extended_case_text(case, Path(case_path).read_text(), d, model.value)
        if json_out == "-":
            typer.echo(json.dumps(result, indent=2, default=float))
            if extended_case:
                write_text_atomic(extended_case, text)
            return
        if json_out:
            write_text_atomic(json_out, json.dumps(result, indent=2, default=float))
        if extended_case:
            write_text_atomic(extended_case, text)
        if report:
            from femcheck.diagnose.report import write_report
            write_report(d, readings, case, measured, report)
        con = console()
        con.print(f"[bold]{escape(case.meta.name)}[/] vs {escape(str(measured))}: model [bold]{escape(d.model_name)}[/]; "
                  f"{readings.n_cases} cases, reading uncertainty {readings.reading_sigma_m * 1e6:.2f} um")
        res = result["residual"]
        con.print(f"verdict: [bold]{d.verdict}[/]  (chi2/dof {res['chi2_per_dof']:.2f}, p {res['p_value']:.2g}, "
                  f"sigma {res['sigma_m'] * 1e6:.2f} um {escape(res['sigma_source'])}, unexplained fraction "
                  f"{res['unexplained_fraction']:.2f}; residual shape: {', '.join(res['shape']['shape'])})")
        if d.weighing.ambiguous:
            con.print(f"[yellow]ambiguous:[/] {escape(d.weighing.ambiguity)}")
        t = Table(title="no significant cause (none)" if not d.significant else
                  "partial explanations (a significant residual remains)" if d.verdict == "unexplained" else
                  "named causes, most important first (held-out error lost without the cause)")
        for h in ("cause", "probability", "held-out loss (% points)", "location", "parameters (95 % interval)"):
            t.add_column(h)
        for c in d.causes:
            t.add_row(escape(c.id), f"{c.probability:.2f}", f"{c.heldout_loss_pct:.1f}", escape(c.location),
                      escape("; ".join(f"{k} = {v:.4g} [{c.params_ci[k][0]:.3g}, {c.params_ci[k][1]:.3g}]"
                                       for k, v in c.params.items())))
        con.print(t)
        e = Table(title="held-out mean relative error of the deflection (%)")
        keys = list(d.heldout_error_before)
        e.add_column("model")
        for k in keys:
            e.add_column(k, justify="right")
        e.add_row("as given", *[f"{100 * d.heldout_error_before[k]:.1f}" for k in keys])
        e.add_row("extended", *[f"{100 * d.heldout_error_after[k]:.1f}" for k in keys])
        if d.baseline_error:
            e.add_row("seed 001 weight fit", *[f"{100 * d.baseline_error.get(k, float('nan')):.1f}" for k in keys])
        con.print(e)
        for w in list(d.warnings) + mismatch:
            con.print(f"[yellow]warning:[/] {escape(w)}")
        if report:
            con.print(f"report: {escape(str(Path(report) / 'report.html'))}")


def _refuse_implausible_scale(model, readings, measured) -> None:
    """Exit 2 (one line naming the likely unit) when the measured eq. 1 deflections along the load are more than 10x
    off, either way, the ones the case's model predicts (:func:`femcheck.diagnose.plausibility.scale_check`)."""
    import numpy as np

    from femcheck.diagnose import predict_readings
    from femcheck.diagnose.plausibility import scale_check
    from femcheck.errors import MeasuredDataError

    if readings.n_cases == 0:
        return
    pred = predict_readings(model, readings)
    along = lambda d: np.einsum("ij,ij->i", d, readings.case_unit)
    _, problem = scale_check(along(readings.delta), along(pred[readings.total_state] - pred[readings.preload_state]))
    if problem:
        raise MeasuredDataError(measured, None, "dx_mm..dz_mm", problem)


def _diagnose_serial(case, case_path, measured, json_out, report, sigma_mm, folds, extended_case=None,
                     compensation=None, poses=None) -> None:
    """Self-weight diagnosis of a serial robot (a kinematic tree) from absolute marker positions."""
    import math

    from femcheck.cli import progress
    from femcheck.cli._common import emit_json
    from femcheck.errors import CaseError
    from femcheck.robot.diagnosis import diagnose_tree
    from femcheck.robot.positions import read_marker_csv
    from femcheck.robot.serial_case import as_tree_case

    if sigma_mm is not None and not (math.isfinite(sigma_mm) and sigma_mm > 0):
        raise CaseError(case_path, "--sigma-mm", f"got {sigma_mm}; expected a positive number of mm")
    case = as_tree_case(case)
    tree = case.tree
    data = read_marker_csv(measured, tree.marker_names, tree.n_joints,
                           tree.independent if tree.n_rows > tree.n_joints else None,
                           tree.prismatic if tree.prismatic.any() else None)
    if data.n_poses < 10:
        from femcheck.errors import MeasuredDataError
        raise MeasuredDataError(measured, None, "pose", f"{data.n_poses} poses; expected at least 10 for a diagnosis")
    with progress("diagnose", None) as bar:
        d = diagnose_tree(case, data, sigma_m=None if sigma_mm is None else sigma_mm * 1e-3, folds=folds,
                          progress=lambda s: bar.update(description=s))
    result = {"case": case.source, "case_sha256": case.sha256, "measured": str(measured), **d.as_json()}
    if extended_case or compensation:
        from femcheck.cli._extended_case import write_serial_outputs
        write_serial_outputs(case, case_path, d, extended_case, compensation, poses)
    if json_out:
        emit_json(result, json_out, inputs=[case_path, measured])
        if json_out == "-":
            return
    if report:
        from femcheck.robot.report import write_report
        write_report(d, case, measured, report)
    con = console()
    res = result["residual"]
    con.print(f"[bold]{escape(case.meta.name)}[/] vs {escape(str(measured))}: {data.n_poses} poses, {data.n_readings} marker readings; "
              f"sigma {res['sigma_m'] * 1e3:.3f} mm ({escape(d.sigma_source)})")
    con.print(f"verdict: [bold]{d.verdict}[/]  (chi2/dof {res['chi2_per_dof']:.2f}, p {res['p_value']:.2g}; model as given "
              f"{res['chi2_per_dof_none']:.2f}; unexplained fraction {res['unexplained_fraction']:.2f})")
    if result["ambiguous"]:
        con.print(f"[yellow]ambiguous:[/] {escape(result['ambiguity'])}")
    t = Table(title="partial explanations (a significant residual remains)" if d.verdict == "unexplained" else
              "named causes" if d.verdict == "explained" else "no significant cause (none)")
    for h in ("cause", "probability", "where", "parameters (95 % interval)"):
        t.add_column(h)
    for c in result["causes"]:
        t.add_row(escape(c["id"]), f"{c['probability']:.2f}", escape(c["location"]),
                  escape("; ".join(f"{k} = {v:.4g} [{c['params_ci'][k][0]:.3g}, {c['params_ci'][k][1]:.3g}]"
                                   for k, v in c["params"].items())))
    con.print(t)
    e = Table(title=f"held-out marker error, mm ({result['heldout_folds']}-fold over poses)")
    for h in ("model", "mean", "median", "max"):
        e.add_column(h, justify="right")
    e.add_row("as given", *(f"{result[f'heldout_{k}_error_mm_before']:.3f}" for k in ("mean", "median", "max")))
    e.add_row("extended", *(f"{result[f'heldout_{k}_error_mm_after']:.3f}" for k in ("mean", "median", "max")))
    for l in result["leave_one_out"]:
        e.add_row(f"without {escape(l['id'])}", f"{l['heldout_mean_error_mm']:.3f}", "", f"{l['heldout_max_error_mm']:.3f}")
    con.print(e)
    idf = result["identifiability"]
    con.print(f"nuisance: rank {idf['rank']}/{idf['n_params']}, condition {idf['condition_number']:.3g}, "
              f"{len(idf['fixed'])} fixed at nominal")
    for w in result["not_applicable"] + result["warnings"]:
        con.print(f"[yellow]note:[/] {escape(w)}")
    if report:
        con.print(f"report: {escape(str(Path(report) / 'report.html'))}")
