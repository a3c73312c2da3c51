"""``femcheck deflect CASE --pose ... [--deg] [--mm] --wrench fx,fy,fz,mx,my,mz [--json OUT]``: VJM tool-point deflection.

``--pose`` takes lengths in m and angles in rad, as in every command (``--deg``: angles in degrees, ``--mm``:
lengths in mm):

* ``serial_robot`` case: ``--pose q1,...,qn`` joint angles.
* ``parallel_vjm`` case: ``--pose x,y,z`` the platform point P (base frame; the HISS is a 3-T device, its
  orientation is fixed), or the name of a test point of the case (``--pose TP3``).

The wrench is SI (N, N m) in the base frame at the tool point. Prints the displacement (um) and rotation
(mrad); ``--json OUT`` writes one object instead (``--json -``: on standard output) with ``pose`` in SI (rad, or
m), ``deflection`` = [dx, dy, dz, rx, ry, rz] (m, rad) and ``K``, the 6x6 stiffness (N/m, N/rad, N m/rad;
pseudo-inverse of the compliance at a singular posture, see ``rank``).
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np
import typer

from femcheck.cli._common import DEG_OPTION, JSON_HELP, MM_OPTION, POSE_UNITS, emit_json

from femcheck.errors import FemcheckError


def _numbers(text: str, what: str, count: int | None = None) -> np.ndarray:
    try:
        vals = np.array([float(v) for v in text.replace(" ", "").split(",") if v != ""], dtype=float)
    except ValueError:
        raise FemcheckError(f"{what} {text!r}: expected comma-separated numbers") from None
    if count is not None and vals.size != count:
        raise FemcheckError(f"{what} {text!r}: got {vals.size} values; expected {count}")
    if not np.all(np.isfinite(vals)):
        raise FemcheckError(f"{what} {text!r}: values must be finite")
    return vals


def deflect_case(case, pose: str, wrench: np.ndarray, complementary: bool | None = None, vjm: str | None = None,
                 *, deg: bool = False, mm: bool = False) -> dict:
    """Deflection of a loaded case at ``pose`` (CLI text, m and rad unless ``mm`` / ``deg``) under ``wrench``
    (6,) N, N m -> a JSON-ready dict."""
    from femcheck.cli._common import parse_pose

    if case.kind == "serial_robot":
        from femcheck.vjm.serial_vjm import deflect

        q = parse_pose(pose, 0, case.n_joints, deg=deg)
        ext = None if vjm is None else vjm == "extended"
        if ext and case.model.vjm != "extended":
            raise FemcheckError(f"--vjm extended: {case.source} has no tilt springs (model.vjm = 'conventional')")
        model = case.vjm(extended=ext)
        use_kc = case.model.complementary_stiffness if complementary is None else complementary
        res = deflect(model, q[None, :], wrench, complementary=use_kc)
        return {"case": case.source, "kind": case.kind, "vjm": "extended" if model.extended else "conventional",
                "pose": q.tolist(), "pose_unit": "rad (joint angles)", "wrench": wrench.tolist(),
                "complementary_stiffness": bool(use_kc), "deflection": res.twist[0].tolist(), "K": res.K[0].tolist(),
                "rank": int(res.rank[0]), "joint_torque_Nm": res.joint_torque[0].tolist()}
    if case.kind == "parallel_vjm":
        from femcheck.vjm.rcube_geometry import forward_position, rcube_stiffness

        geom = case.rcube
        try:
            tp = case.test_point(pose.strip())
            P = forward_position(geom, np.deg2rad(tp.active_deg))[0]
            label = tp.name
        except KeyError:
            P = parse_pose(pose, 3, 0, mm=mm)
            label = pose
        _, K = rcube_stiffness(geom, case.K_theta, P[None, :], label=label)
        C = np.linalg.inv(K[0])
        return {"case": case.source, "kind": case.kind, "pose": P.tolist(), "pose_unit": "m (platform point P)",
                "pose_label": label, "wrench": wrench.tolist(), "complementary_stiffness": False,
                "deflection": (C @ wrench).tolist(), "K": K[0].tolist(), "rank": int(np.linalg.matrix_rank(K[0]))}
    raise FemcheckError(f"{case.source}: case kind {case.kind!r} has no VJM deflection; use a serial_robot or parallel_vjm case")


def register(app: typer.Typer) -> None:
    @app.command("deflect")
    def deflect_cmd(
        case_path: Path = typer.Argument(..., metavar="CASE", help="serial_robot or parallel_vjm case file (TOML)"),
        pose: str = typer.Option(..., "--pose", help="serial: joint angles q1,...,qn; parallel: platform x,y,z or a "
                                 "test-point name (" + POSE_UNITS + ")"),
        deg: bool = DEG_OPTION,
        mm: bool = MM_OPTION,
        wrench: str = typer.Option(..., "--wrench", help="fx,fy,fz,mx,my,mz in N and N m (base frame, tool point)"),
        no_complementary: bool = typer.Option(False, "--no-complementary", help="neglect K_C (seed 003 eq. 14)"),
        vjm: Optional[str] = typer.Option(None, "--vjm", help="conventional | extended (default: the case's model.vjm)"),
        json_out: Optional[str] = typer.Option(None, "--json", metavar="OUT", help=JSON_HELP),
    ) -> None:
        """Tool-point deflection of a robot under a wrench (virtual joint method, seeds 001-003)."""
        from femcheck.case import load_case

        if vjm is not None and vjm not in ("conventional", "extended"):
            raise FemcheckError(f"--vjm {vjm!r}: expected conventional or extended")
        case = load_case(case_path)
        W = _numbers(wrench, "--wrench", 6)
        out = deflect_case(case, pose, W, complementary=False if no_complementary else None, vjm=vjm, deg=deg, mm=mm)
        if json_out:
            emit_json(out, json_out, inputs=[case_path])
            return
        from rich.console import Console
        from rich.table import Table

        d = np.asarray(out["deflection"])
        pose_txt = ", ".join(f"{v:g}" for v in out["pose"])
        wrench_txt = ", ".join(f"{v:g}" for v in out["wrench"])
        kc = ('K_C on' if out['complementary_stiffness'] else 'K_C off') if out['kind'] == 'serial_robot' else 'passive joints free'
        typer.echo(f"{case_path} ({out.get('vjm', 'parallel')} VJM, {kc})")
        typer.echo(f"pose [{pose_txt}] {out['pose_unit']}; wrench [{wrench_txt}] N, N m")
        t = Table(title="tool-point deflection")
        t.add_column("component")
        t.add_column("value", justify="right")
        t.add_column("unit")
        for name, v in zip(("dx", "dy", "dz"), d[:3]):
            t.add_row(name, f"{v * 1e6:.3f}", "um")
        t.add_row("|d|", f"{np.linalg.norm(d[:3]) * 1e6:.3f}", "um")
        for name, v in zip(("rx", "ry", "rz"), d[3:]):
            t.add_row(name, f"{v * 1e3:.5f}", "mrad")
        t.add_row("rank C", str(out["rank"]), "")
        Console().print(t)
        K = np.asarray(out["K"])
        typer.echo("translational stiffness diag(K[:3,:3]) = " + ", ".join(f"{k / 1e6:.4g}" for k in np.diag(K)[:3]) + " N/um")
        if out["rank"] < 6:
            typer.echo(f"singular posture: rank {out['rank']}; K is the pseudo-inverse of the compliance")
