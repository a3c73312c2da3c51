"""``femcheck sweep``: parameter sweeps of the analytical stiffness models or the device FE model,
sensitivity, HTML summary."""
from __future__ import annotations

from enum import Enum

import typer

from femcheck.cli._common import Joints, ModelLevel, load_case_for


class Design(str, Enum):
    grid = "grid"
    lhs = "lhs"
    sobol = "sobol"


class SweepModel(str, Enum):
    simplified = "simplified"
    detailed = "detailed"
    fe = "fe"


class MeshLevel(str, Enum):
    """Mesh level of ``--model fe`` (``femcheck.fe_device.mesh_levels``)."""
    coarse = "coarse"
    default = "default"
    fine = "fine"


def register(app: typer.Typer) -> None:
    @app.command("sweep")
    def sweep_cmd(
        case_path: str = typer.Argument(..., metavar="CASE", help="case file (TOML), e.g. cases/haptic_6psu.toml"),
        param: list[str] = typer.Option(..., "--param", help="KEY=LO:HI[:N|log], SI units of the key; repeat per parameter"),
        design: Design = typer.Option(Design.lhs, "--design", help="grid (levels N per key), lhs, or sobol (Saltelli, gives Sobol' indices)"),
        samples: int = typer.Option(None, "--samples", help="lhs: samples; sobol: base samples n (power of 2; n (d+2) runs); grid: default levels"),
        model: SweepModel = typer.Option(SweepModel.detailed, "--model", help="simplified | detailed | fe (whole-device FE, one sample per task)"),
        fe_level: ModelLevel = typer.Option(None, "--fe-level", help="--model fe only: FE level simplified | detailed (default detailed)"),
        mesh: MeshLevel = typer.Option(None, "--mesh", help="--model fe only: mesh level coarse | default | fine (default coarse)"),
        joints: Joints = typer.Option(None, "--joints", help="joint idealization; default: the case's model.joint_rotations"),
        points: str = typer.Option("cube", "--points", help="cube (P0..P8) or a list such as P0,P3"),
        out: str = typer.Option(None, "--out", help="output folder (default reports/sweep/<case name>)"),
        scheduler: str = typer.Option(None, "--scheduler", help="Dask scheduler address tcp://host:port (or env FEMCHECK_SCHEDULER)"),
        resume: bool = typer.Option(False, "--resume", help="continue a sweep in --out, skipping finished samples"),
        jobs: int = typer.Option(None, "--jobs", help="local worker processes (default: CPU count; 0 = in this process)"),
        seed: int = typer.Option(0, "--seed", help="seed of the lhs / sobol design"),
        chunk: int = typer.Option(None, "--chunk", help="samples per task (default about 20,000 sample-points; 1 for --model fe)"),
        no_report: bool = typer.Option(False, "--no-report", help="skip the HTML summary"),
    ):
        """Sweep case parameters; store results (Parquet), elasticities, Sobol' indices and an HTML summary.

        Example: femcheck sweep cases/haptic_6psu.toml --param guideway.width_radial_m=0.010:0.020
        --param proximal_link.outer_diameter_m=0.006:0.010 --design sobol --samples 256
        """
        from pathlib import Path

        from rich.table import Table

        from femcheck.cli import console
        from femcheck.report.atomic import refuse_input_overwrite
        from femcheck.sweep.analysis import analyse, local_elasticities
        from femcheck.sweep.parameters import parse_params
        from femcheck.sweep.report import write_report
        from femcheck.sweep.run import parse_points, preflight, run_sweep

        if model != SweepModel.fe and (fe_level is not None or mesh is not None):
            raise typer.BadParameter(f"{'--fe-level' if fe_level is not None else '--mesh'} applies to --model fe only "
                                     f"(got --model {model.value})")
        fe_level_value = (fe_level or ModelLevel.detailed).value
        mesh_value = (mesh or MeshLevel.coarse).value
        case = load_case_for(case_path, "sweep", kinds=("haptic_6psu", "parallel_device"))
        if case.kind == "parallel_device" and model == SweepModel.fe:
            raise typer.BadParameter("--model fe: not available for parallel_device cases yet; use simplified or detailed")
        ranges = parse_params(case, list(param))
        pts = parse_points(points)
        out_dir = Path(out) if out else Path("reports/sweep") / Path(case_path).stem
        refuse_input_overwrite(out_dir, [case_path])
        preflight(case, out_dir, model=model.value, joints=joints.value if joints else None, resume=resume,
                  fe_level=fe_level_value, mesh=mesh_value)
        con = console()
        con.print(f"[bold]{case.meta.name}[/]: sweeping " + ", ".join(
            f"{r.key} {r.lo:g}..{r.hi:g}{' (log)' if r.log else ''}" for r in ranges)
            + f" — design {design.value}, model {model.value}"
            + (f" (FE level {fe_level_value}, mesh {mesh_value})" if model == SweepModel.fe else "")
            + f", points {','.join(pts)}")
        from femcheck.cli import progress
        with progress("sweep tasks", None, con) as bar:
            try:
                outcome = run_sweep(case, ranges, out_dir, design=design.value, samples=samples, seed=seed,
                                    model=model.value, joints=joints.value if joints else None, points=pts,
                                    scheduler=scheduler, jobs=jobs, resume=resume, chunk_samples=chunk,
                                    fe_level=fe_level_value, mesh=mesh_value,
                                    on_progress=lambda done, total: bar.update(completed=done, total=total))
            except KeyboardInterrupt:
                con.print(f"[red]interrupted[/]: the workers were stopped; finished tasks are stored in {out_dir}; "
                          "run the same command with --resume to finish")
                raise typer.Exit(130) from None
        man = outcome.manifest
        t = man["timing"]
        rate = t.get("sample_points_per_s")
        con.print(f"{man['design']['samples']} samples x {len(pts)} points = {man['sample_points']} sample-points; "
                  f"evaluated {t['sample_points_evaluated']} this run in {t['compute_wall_s']:.2f} s on {t['backend']} "
                  f"({t['workers']} workers)" + (f", {rate:.3g} sample-points/s" if rate else "")
                  + f"; {man['resumed_with_finished_samples']} samples reused")
        an = analyse(outcome)
        if not an.ok.all():
            con.print(f"[yellow]{int((~an.ok).sum())} of {an.ok.size} samples could not be evaluated at every point "
                      "(unreachable or not converged); they are stored with ok = false and NaN results"
                      + (" (the failure column says why)" if model == SweepModel.fe else "") + "[/]")
        # local elasticities need 2 d extra evaluations at the nominal design: for an FE sweep (2 d more FE
        # solves) they come from the analytical model of the same level, said in the title and kept out of
        # the HTML summary (whose local column does not say which model it comes from)
        local_model = fe_level_value if model == SweepModel.fe else model.value
        local = local_elasticities(case, ranges, model=local_model, joints=joints.value if joints else None, points=pts)
        tab = Table(title="elasticity d ln k_min / d ln p (global over the box | local at nominal"
                    + (f", analytical {local_model} model)" if model == SweepModel.fe else ")"))
        tab.add_column("load")
        for r in ranges:
            tab.add_column(r.key, justify="right")
        for name in an.elasticity:
            tab.add_row(name, *[f"{g:.3f} | {l:.3f}" for g, l in zip(an.elasticity[name], local[name])])
        con.print(tab)
        if an.sobol_first is not None:
            st = Table(title=f"Sobol' indices of k_min ({an.sobol_method})")
            st.add_column("output")
            for r in ranges:
                st.add_column(r.key, justify="right")
            for name, s in an.sobol_first.items():
                tot = an.sobol_total[name] if an.sobol_total is not None else [float("nan")] * len(s)
                st.add_row(name, *[f"S {a:.3f} / ST {b:.3f}" for a, b in zip(s, tot)])
            con.print(st)
        con.print(f"results: {outcome.store.results_path}  manifest: {outcome.store.manifest_path}")
        if not no_report:
            con.print(f"summary: {write_report(outcome, an, None if model == SweepModel.fe else local)}")
