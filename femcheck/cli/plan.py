"""``femcheck plan CASE DATA.csv [--budget N] [--json OUT]``: the next measurements that best separate the rival
explanations of a diagnosis."""
from __future__ import annotations

from typing import Optional

import typer

from femcheck.cli._common import JSON_HELP, Joints, ModelLevel, emit_json, load_case_for


def register(app: typer.Typer) -> None:
    @app.command("plan")
    def plan_cmd(
        case_path: str = typer.Argument(..., metavar="CASE", help="case file (TOML), e.g. cases/haptic_6psu.toml"),
        measured: str = typer.Argument(..., metavar="DATA.csv", help="measured-data CSV (docs/diagnose.md)"),
        budget: int = typer.Option(3, "--budget", min=1, max=20, help="number of measurements to propose"),
        json_out: Optional[str] = typer.Option(None, "--json", metavar="OUT", help=JSON_HELP),
        model: ModelLevel = typer.Option(ModelLevel.detailed, "--model", help="analytical model to check"),
        joints: Joints = typer.Option(None, "--joints", help="joint idealization; default: the case's [model] joint_rotations"),
        effects: Optional[str] = typer.Option(None, "--effects", metavar="ID,ID",
                                              help="restrict the diagnosis to these effects (default: the whole library)"),
        poses: int = typer.Option(120, "--poses", min=1, max=2000, help="workspace poses sampled besides the 9 cube points"),
        rivals: int = typer.Option(5, "--rivals", min=2, max=10, help="most rival explanations to separate"),
        max_condition: float = typer.Option(None, "--max-condition", help="cond(J_h) limit of a planned pose (default 10)"),
        seed: int = typer.Option(0, "--seed", help="seed of the scrambled Sobol' pose sample"),
        tilt_deg: float = typer.Option(None, "--tilt-deg", help="platform tilt sampled about each axis, deg "
                                       "(default 10; 0: the case's orientation only)"),
        pose_table: Optional[str] = typer.Option(None, "--pose-table", metavar="PLAN.json",
                                                 help="pose table for point ids other than P0..P8: an earlier plan's JSON"),
    ):
        """Diagnose DATA.csv, take the top rival explanations (posterior-weighted) and propose the N measurements
        (pose in the reachable workspace, load direction, load level) that best separate them, with the expected
        posterior of the leading cause after them."""
        import numpy as np

        from femcheck.cli import console
        from femcheck.diagnose import AnalyticalChainModel, diagnose
        from femcheck.diagnose.effects import effects as effect_registry
        from femcheck.diagnose.plan import PLAN_MAX_CONDITION, TILT_RAD, plan_measurements
        from femcheck.measured import process, read_measured_csv

        if json_out and json_out != "-":
            from femcheck.report.atomic import check_output_file, refuse_input_overwrite
            check_output_file(json_out, "--json")
            refuse_input_overwrite(json_out, [case_path, measured])
        limit = PLAN_MAX_CONDITION if max_condition is None else max_condition
        tilt = TILT_RAD if tilt_deg is None else float(np.deg2rad(tilt_deg))
        if not (tilt == tilt and 0.0 <= tilt <= np.pi / 2):
            raise typer.BadParameter(f"--tilt-deg: {tilt_deg}; expected a number of degrees from 0 to 90")
        if not (limit == limit and 1.0 < limit < float("inf")):
            raise typer.BadParameter(f"--max-condition: {max_condition}; expected a finite number > 1")
        pool = None
        if effects:
            reg = effect_registry()
            pool = [e.strip() for e in effects.split(",") if e.strip()]
            bad = [e for e in pool if e not in reg or e == "none"]
            if bad or not pool:
                raise typer.BadParameter(f"--effects: {bad[0] if bad else effects!r} is not an effect; expected ids from "
                                         f"{', '.join(sorted(k for k in reg if k != 'none'))}")
        case = load_case_for(case_path, "plan")
        table = None
        if pose_table:
            from femcheck.diagnose.plan import read_pose_table
            table = read_pose_table(pose_table, case)
        readings = process(read_measured_csv(measured), case, table)
        m = AnalyticalChainModel(case, model.value, joints.value if joints else case.model.joint_rotations)
        from femcheck.cli import progress
        with progress("diagnose", None, stderr=json_out == "-") as bar:
            d = diagnose(m, readings, candidates=pool, with_baseline=False, progress=bar)
        # the plan itself: no count of steps to give an ETA for; the heartbeat shows that it runs
        with progress("plan", None, stderr=json_out == "-"):
            p = plan_measurements(m, readings, d.weighing, budget=budget, n_poses=poses, rivals=rivals, seed=seed,
                                  max_condition=limit, tilt_rad=tilt)
        result = {"case": case.source, "case_sha256": case.sha256, "measured": str(measured), "model": d.model_name,
                  "verdict": d.verdict, "ambiguous": d.weighing.ambiguous, "ambiguity": d.weighing.ambiguity,
                  **p.as_json()}
        if json_out:
            emit_json(result, json_out, inputs=[case_path, measured])
            if json_out == "-":
                return
        from rich.table import Table
        con = console()
        con.print(f"[bold]{case.meta.name}[/] vs {measured}: model [bold]{d.model_name}[/]; verdict [bold]{d.verdict}[/]"
                  + (f"; [yellow]{d.weighing.ambiguity}[/]" if d.weighing.ambiguous else ""))
        r = Table(title=f"rival explanations ({100 * p.rival_mass:.1f} % of the posterior)")
        for h in ("explanation", "probability now", "expected posterior after the plan, if true"):
            r.add_column(h, justify="left" if h == "explanation" else "right")
        for rv in p.rivals:
            r.add_row("+".join(rv["ids"]), f"{rv['probability']:.3f}", f"{rv['expected_posterior_if_true']:.3f}")
        con.print(r)
        t = Table(title=f"proposed measurements (preload {p.measurements[0].preload_N:g} N, then preload + load; "
                        f"{p.trials} trials; forces only)")
        for h in ("#", "pose", "x mm", "y mm", "z mm", "orientation deg (rot. vector)", "cond", "direction", "u", "load N",
                  "objective after"):
            t.add_column(h, justify="left" if h in ("pose", "direction", "u") else "right")
        for k, mm in enumerate(p.measurements, 1):
            x, y, z = (v * 1e3 for v in mm.pose[:3])
            rot = "(" + ", ".join(f"{v:+.1f}" for v in np.rad2deg(mm.pose[3:])) + ")"
            t.add_row(str(k), mm.pose_id, f"{x:.1f}", f"{y:.1f}", f"{z:.1f}", rot, f"{mm.cond:.2f}", mm.direction_label,
                      "(" + ", ".join(f"{v:+.3f}" for v in mm.direction) + ")", f"{mm.load_N:g}", f"{mm.objective_after:.4f}")
        con.print(t)
        lead = "+".join(p.rivals[0]["ids"])
        con.print(f"criterion: expected log Bayes factor {lead} over {'+'.join(p.rivals[1]['ids'])}: "
                  f"{p.log_bayes_factor_top2_now:.2f} now -> {p.expected_log_bayes_factor_top2:.2f} after the plan if "
                  f"{lead} is true ({p.expected_log_bayes_factor_top2_reverse:.2f} the other way round); "
                  f"objective {p.objective_before:.4f} -> {p.objective_after:.4f}")
        causes = ", ".join(f"{c} {v:.3f}" for c, v in p.expected_cause_probability_leader.items()) or "none"
        con.print(f"expected posterior of the leading explanation {lead}: {p.rivals[0]['probability']:.3f} now -> "
                  f"{p.expected_posterior_leader:.3f} (its causes: {causes}); {p.n_candidates} candidates "
                  f"({p.n_candidate_poses} poses x 26 directions x {len(p.load_levels_N)} loads), {p.wall_s:.1f} s")
        for n in p.notes:
            con.print(f"note: {n}")
