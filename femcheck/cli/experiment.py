"""``femcheck experiment simulate``: a virtual stiffness experiment with hidden effects."""
from __future__ import annotations

import json
from pathlib import Path

import typer

from femcheck.cli._common import load_case_for
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
        joint_mesh: str = typer.Option("coarse", "--joint-mesh", help="--model fe: mesh of the joint contact FE "
                                       "(the joint laws, as femcheck verify): coarse | default | fine"),
        no_sweep: bool = typer.Option(False, "--no-sweep", help="omit the preload-identification staircase at P0"),
        force: bool = typer.Option(False, "--force", help="overwrite existing output files"),
        poses: int = typer.Option(300, "--poses", min=10, help="serial robots: random poses (all markers at each)"),
        sigma_mm: float = typer.Option(0.2, "--sigma-mm", help="serial robots: Gaussian noise per coordinate, mm"),
        foreign: list[str] = typer.Option([], "--foreign", help="serial robots: an effect outside the vocabulary, "
                                          "NAME=VALUE with NAME drift | sensor_scale | compliant_base | cross_talk"),
    ):
        """Readings of the paper's protocol (9 points, directions, preload, trials, dial resolution + noise); for a
        serial robot (serial_tree case), absolute marker positions at random poses under self-weight, with random
        geometric errors and sensor frame, hidden elastic causes (``--effect CAUSE:JOINT=VALUE,...``, JOINT a row
        name or ``all``) and foreign effects."""
        from femcheck.experiment.simulate import parse_effect_spec, simulate
        from femcheck.report.atomic import check_output_file, refuse_input_overwrite, write_text_atomic

        check_output_file(out, "--out")
        check_output_file(truth, "--truth")
        if Path(out).resolve() == Path(truth).resolve():
            raise FemcheckError(f"--out and --truth are the same file: {out}")
        for p in (out, truth):
            refuse_input_overwrite(p, [case_path])
            if Path(p).exists() and not force:
                raise FemcheckError(f"refusing to overwrite existing {p} (use --force)")
        case = load_case_for(case_path, "experiment simulate", kinds=("haptic_6psu", "serial_tree", "serial_robot"))
        if case.meta.kind in ("serial_tree", "serial_robot"):
            return _simulate_serial(case, effect, foreign, seed, poses, sigma_mm, out, truth)
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
            from femcheck.diagnose.fe_model import device_fe_reading_model
            from femcheck.fe_device.mesh_levels import MESH_LEVELS
            from femcheck.kinematics.psu6 import POINT_LABELS
            if mesh not in MESH_LEVELS:
                raise typer.BadParameter(f"{mesh!r}; expected one of {', '.join(MESH_LEVELS)}", param_hint="--mesh")
            if parts not in ("solid", "beam"):
                raise typer.BadParameter(f"{parts!r}; expected solid or beam", param_hint="--parts")
            if joint_mesh not in MESH_LEVELS:
                raise typer.BadParameter(f"{joint_mesh!r}; expected one of {', '.join(MESH_LEVELS)}",
                                         param_hint="--joint-mesh")
            typer.echo(f"device FE ({parts} parts, mesh {mesh}, joint laws from the contact FE at the {joint_mesh} "
                       "joint mesh, as femcheck verify) at the 9 test points ...")
            reading_model = device_fe_reading_model(case, POINT_LABELS, mesh, parts, joint_mesh)
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


def _simulate_serial(case, effect, foreign, seed, poses, sigma_mm, out, truth) -> None:
    import math

    from femcheck.report.atomic import write_text_atomic
    from femcheck.robot.causes import CAUSE_IDS
    from femcheck.robot.positions import format_marker_csv
    from femcheck.robot.serial_case import as_tree_case
    from femcheck.robot.simulate import FOREIGN, simulate_positions

    case = as_tree_case(case)
    tree = case.tree

    def number(text, hint):
        try:
            v = float(text)
        except ValueError:
            raise typer.BadParameter(f"{text!r} is not a number", param_hint=hint) from None
        if not math.isfinite(v):
            raise typer.BadParameter(f"{text!r}; expected a finite number", param_hint=hint)
        return v

    effects: dict = {}
    for spec in effect:
        cid, _, rest = spec.partition(":")
        if cid not in CAUSE_IDS:
            raise typer.BadParameter(f"{cid!r}; expected one of {', '.join(CAUSE_IDS)}", param_hint="--effect")
        if not rest:
            raise typer.BadParameter(f"{spec!r}; expected {cid}:JOINT=VALUE[,JOINT=VALUE] (JOINT a row or 'all')",
                                     param_hint="--effect")
        for item in rest.split(","):
            name, _, val = item.partition("=")
            if name != "all" and name not in tree.names:
                raise typer.BadParameter(f"{name!r} is not a row of the case; expected 'all' or one of {list(tree.names)}",
                                         param_hint="--effect")
            effects.setdefault(cid, {})[name] = number(val, "--effect")
    fx = {}
    for spec in foreign:
        name, _, val = spec.partition("=")
        if name not in FOREIGN:
            raise typer.BadParameter(f"{name!r}; expected one of {', '.join(FOREIGN)}", param_hint="--foreign")
        fx[name] = number(val, "--foreign")
    if not (math.isfinite(sigma_mm) and sigma_mm >= 0):
        raise typer.BadParameter(f"{sigma_mm}; expected >= 0", param_hint="--sigma-mm")
    data, tr = simulate_positions(case, poses, effects=effects, foreign=fx, sigma_m=sigma_mm * 1e-3, seed=seed)
    write_text_atomic(out, format_marker_csv(data, tree.marker_names, meta={"generated_by": "femcheck experiment simulate",
                                                                             "seed": seed},
                                             prismatic=tree.prismatic[tree.independent]))
    write_text_atomic(truth, json.dumps({"effects": effects, "foreign": fx, "sigma_m": sigma_mm * 1e-3, "seed": seed,
                                         "mass_scale": tr["params"].mass_scale,
                                         "sensor_rotation": tr["sensor_R"].tolist(), "sensor_translation_m": tr["sensor_t"].tolist()},
                                        indent=2))
    typer.echo(f"wrote {data.n_readings} marker readings ({data.n_poses} poses) to {out}; hidden truth to {truth}")
