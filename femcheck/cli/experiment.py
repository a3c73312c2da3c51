"""``femcheck experiment simulate``: a virtual stiffness experiment with hidden effects (issue 7 item 8)."""
from __future__ import annotations

import json
from pathlib import Path

import typer

from femcheck.case import load_case
from femcheck.errors import FemcheckError


def register(app: typer.Typer) -> None:
    exp = typer.Typer(help="Virtual experiments (synthetic measured data with hidden model errors).", no_args_is_help=True)

    @exp.command("simulate")
    def simulate_cmd(
        case_path: str = typer.Argument(..., metavar="CASE", help="case file (TOML)"),
        effect: list[str] = typer.Option([], "--effect", help="hidden effect ID[:param=value,...] (repeatable); "
                                         "without parameters a random magnitude and location is drawn"),
        seed: int = typer.Option(0, "--seed", help="seed of the noise and of random effect magnitudes"),
        out: str = typer.Option(..., "--out", help="measured-data CSV to write"),
        truth: str = typer.Option(..., "--truth", help="JSON file for the hidden truth (never in the CSV)"),
        directions: str = typer.Option("+x,-x,+y,-y,+z,-z", "--directions", help="load directions, comma-separated"),
        model: str = typer.Option("detailed", "--model", help="model the readings come from: detailed or simplified "
                                  "(analytical chain), or fe (device FE, detailed level with frictional contact joints)"),
        joints: str = typer.Option(None, "--joints", help="analytical models: rigid | released (default: the case's)"),
        mesh: str = typer.Option("coarse", "--mesh", help="--model fe: FE mesh coarse | default | fine"),
        parts: str = typer.Option("solid", "--parts", help="--model fe: guideways and links as solid or beam parts"),
        no_sweep: bool = typer.Option(False, "--no-sweep", help="omit the preload-identification staircase at P0"),
        force: bool = typer.Option(False, "--force", help="overwrite existing output files"),
    ):
        """Readings of the paper's protocol (9 points, directions, preload, trials, dial resolution + noise)."""
        from femcheck.experiment.simulate import parse_effect_spec, simulate
        from femcheck.report.atomic import refuse_input_overwrite, write_text_atomic

        if Path(out).resolve() == Path(truth).resolve():
            raise FemcheckError(f"--out and --truth are the same file: {out}")
        from femcheck.cli.diagnose import check_writable
        for p, opt in ((out, "--out"), (truth, "--truth")):
            check_writable(p, opt)
        for p in (out, truth):
            refuse_input_overwrite(p, [case_path])
            if Path(p).exists() and not force:
                raise FemcheckError(f"refusing to overwrite existing {p} (use --force)")
        case = load_case(case_path)
        try:
            hidden = [parse_effect_spec(e) for e in effect]
        except KeyError as exc:
            raise typer.BadParameter(str(exc.args[0]), param_hint="--effect") from None
        dirs = tuple(d.strip() for d in directions.split(",") if d.strip())
        bad = [d for d in dirs if d not in ("+x", "-x", "+y", "-y", "+z", "-z")]
        if bad:
            raise typer.BadParameter(f"{bad[0]!r}; expected +x, -x, +y, -y, +z, -z", param_hint="--directions")
        if model not in ("detailed", "simplified", "fe"):
            raise typer.BadParameter(f"{model!r}; expected detailed, simplified or fe", param_hint="--model")
        if joints not in (None, "rigid", "released"):
            raise typer.BadParameter(f"{joints!r}; expected rigid or released", param_hint="--joints")
        reading_model = None
        if model == "fe":
            from femcheck.diagnose.fe_model import DeviceFEReadingModel
            from femcheck.fe_device.mesh_levels import MESH_LEVELS
            from femcheck.kinematics.psu6 import POINT_LABELS
            from femcheck.verify.fe import run_fe
            if mesh not in MESH_LEVELS:
                raise typer.BadParameter(f"{mesh!r}; expected one of {', '.join(MESH_LEVELS)}", param_hint="--mesh")
            if parts not in ("solid", "beam"):
                raise typer.BadParameter(f"{parts!r}; expected solid or beam", param_hint="--parts")
            typer.echo(f"device FE ({parts} parts, mesh {mesh}) at the 9 test points ...")
            reading_model = DeviceFEReadingModel(case, run_fe(case, POINT_LABELS, ("detailed",), mesh, jobs=1, kind=parts))
        try:
            ve = simulate(case, hidden, seed=seed, directions=dirs, level="detailed" if model == "fe" else model,
                          joints=joints, sweep=not no_sweep, model=reading_model)
        except ValueError as exc:
            raise typer.BadParameter(str(exc), param_hint="--effect") from None
        write_text_atomic(out, ve.csv_text)
        write_text_atomic(truth, json.dumps(ve.truth, indent=2))
        typer.echo(f"wrote {len(ve.data)} readings to {out}; hidden truth ({', '.join(e['id'] for e in ve.truth['effects'])}) "
                   f"to {truth}")

    app.add_typer(exp, name="experiment")
