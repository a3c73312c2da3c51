"""``femcheck stiffness``: 6x6 TCP stiffness, deflection and element contributions at one pose."""
from __future__ import annotations

from typing import Optional

import numpy as np
import typer

from rich.table import Table

from femcheck.chain import ELEMENT_NAMES, ELEMENTS, evaluate
from femcheck.cli import console
from femcheck.cli._common import (DEG_OPTION, JSON_HELP, MM_OPTION, POSE_UNITS, Joints, ModelLevel, emit_json, load_case_for,
                                  parse_vector, print_contributions, print_directional_stiffness, select_pose)
from femcheck.kinematics.conditioning import DEFAULT_MAX_CONDITION, require_well_conditioned
from femcheck.kinematics.psu6 import condition_number, leg_geometry


def register(app: typer.Typer) -> None:
    @app.command("stiffness")
    def stiffness_cmd(
        case_path: str = typer.Argument(..., metavar="CASE", help="case file (TOML), e.g. cases/haptic_6psu.toml"),
        model: ModelLevel = typer.Option(ModelLevel.detailed, "--model", help="simplified (links) or detailed (links + joints + actuation)"),
        joints: Joints = typer.Option(None, "--joints", help="joint idealization; default: the case's [model] joint_rotations"),
        point: str = typer.Option(None, "--point", help="test point P0..P8 (default P0)"),
        pose: str = typer.Option(None, "--pose", help="TCP pose x,y,z,rx,ry,rz (rotation vector; " + POSE_UNITS + ")"),
        deg: bool = DEG_OPTION,
        mm: bool = MM_OPTION,
        wrench: str = typer.Option(None, "--wrench", help="TCP wrench fx,fy,fz,mx,my,mz (N, N m); default: the case's detailed test load along +z"),
        max_condition: float = typer.Option(DEFAULT_MAX_CONDITION, "--max-condition", help="refuse poses whose cond(J_h) exceeds this (singularity guard; warns above a tenth of it)"),
        json_out: Optional[str] = typer.Option(None, "--json", metavar="OUT", help=JSON_HELP),
    ):
        """6x6 stiffness at the TCP, deflection under a wrench, and the element contributions (seed 000 Fig. 23).

        The detailed model's Hertz contacts are linearized at the given wrench (docs/conventions.md §6).
        Also takes parallel_device cases (hexapods, Delta robots, ...; docs/parallel_device.md).
        """
        case = load_case_for(case_path, "stiffness", kinds=("haptic_6psu", "parallel_device"))
        if case.kind == "parallel_device":
            from femcheck.cli import _parallel_device
            return _parallel_device.stiffness(case, case_path, model=model.value, joints=joints.value if joints else None,
                                              point=point, pose=pose, wrench=wrench, json_out=json_out, deg=deg, mm=mm)
        P, label = select_pose(case, point, pose, deg=deg, mm=mm)
        if not (np.isfinite(max_condition) and max_condition > 1):
            raise typer.BadParameter(f"--max-condition: {max_condition}; expected a finite number > 1")
        cond = require_well_conditioned(case, leg_geometry(case, P, labels=[label]), [label], max_condition)
        warnings = cond.warnings([label])
        W = parse_vector(wrench, 6, "--wrench") if wrench else np.array([0, 0, case.loads.detailed_test_N, 0, 0, 0.0])
        r = evaluate(case, P, W, model=model.value, joints=joints.value if joints else None, labels=[label])
        contrib = {ELEMENT_NAMES[e]: float(r.contributions[0, j]) for j, e in enumerate(ELEMENTS)
                   if r.element_energy[0, :, j].any()}
        if json_out:
            emit_json({"case": case.source, "pose": P[0].tolist(), "point": label, "model": r.model,
                                   "joints": r.joints, "wrench": W.tolist(), "K": r.K[0].tolist(),
                                   "deflection": r.twist[0].tolist(), "contributions": contrib,
                                   "condition_number": float(cond.cond[0]), "max_condition": max_condition,
                                   "warnings": warnings}, json_out, inputs=[case_path])
            return
        con = console()
        for w in warnings:
            con.print(f"[yellow]warning:[/] {w}")
        con.print(f"[bold]{case.meta.name}[/] — {label}, model [bold]{r.model}[/], joints [bold]{r.joints}[/], "
                  f"wrench {np.array2string(W, precision=3)} (N, N m)")
        kt = Table(title="TCP stiffness K (SI: N/m | N/rad ; N m/m | N m/rad)")
        for h in ("", "dx", "dy", "dz", "rx", "ry", "rz"):
            kt.add_column(h, justify="right")
        for i, h in enumerate(("Fx", "Fy", "Fz", "Mx", "My", "Mz")):
            kt.add_row(h, *[f"{v:.4g}" for v in r.K[0, i]])
        con.print(kt)
        t = r.twist[0]
        con.print(f"deflection: d = [{t[0]*1e3:.5f}, {t[1]*1e3:.5f}, {t[2]*1e3:.5f}] mm, "
                  f"theta = [{t[3]*1e3:.5f}, {t[4]*1e3:.5f}, {t[5]*1e3:.5f}] mrad")
        print_directional_stiffness(con, r)
        legs = leg_geometry(case, P)
        con.print(f"Jacobian condition number (homogenized, L = R_p): {condition_number(case, legs)[0]:.3f}; "
                  f"slider positions {np.array2string(legs.slider[0]*1e3, precision=1)} mm")
        print_contributions(con, contrib, "contributions (share of deflection energy, docs/conventions.md §7)")
