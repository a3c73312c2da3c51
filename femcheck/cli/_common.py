"""Shared CLI parsing helpers (vectors on the command line, point selection)."""
from __future__ import annotations

from enum import Enum

import numpy as np
import typer

from femcheck.kinematics.points import point_index
from femcheck.kinematics.psu6 import POINT_LABELS, test_points


class ModelLevel(str, Enum):
    """Analytical model level (seed 000 §3.1 simplified, §3.2 detailed)."""
    simplified = "simplified"
    detailed = "detailed"


class Joints(str, Enum):
    """Joint idealization (docs/conventions.md §5)."""
    rigid = "rigid"
    released = "released"


def parse_vector(text: str, n: int, name: str) -> np.ndarray:
    """'a,b,c' -> float array of length n; a clear usage error otherwise."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise typer.BadParameter(f"{name}: {text!r} is not a comma-separated list of numbers") from None
    if len(values) != n:
        raise typer.BadParameter(f"{name}: expected {n} comma-separated numbers, got {len(values)}")
    bad = [v for v in values if not np.isfinite(v)]
    if bad:
        raise typer.BadParameter(f"{name}: {text!r} contains {bad[0]}; expected {n} finite numbers")
    return np.asarray(values)


#: what every --pose takes: one convention for all commands
POSE_UNITS = "lengths in m and angles in rad; --mm: lengths in mm, --deg: angles in degrees"
#: the options that state other units for --pose (shared by every command that takes a pose)
DEG_OPTION = typer.Option(False, "--deg", help="--pose angles in degrees (default: rad)")
MM_OPTION = typer.Option(False, "--mm", help="--pose lengths in mm (default: m)")
#: a --pose length beyond this (m) or an angle beyond a turn is refused as a likely unit mix-up
POSE_MAX_LENGTH_M = 10.0


def parse_pose(text: str, lengths: int, angles: int, *, deg: bool = False, mm: bool = False,
               name: str = "--pose") -> np.ndarray:
    """``--pose`` text -> SI values (m, rad), ``lengths`` lengths then ``angles`` angles, in the units
    :data:`POSE_UNITS` states. A length above :data:`POSE_MAX_LENGTH_M` or an angle above one turn is refused
    with the option that probably was meant (--mm, --deg): no robot here reaches 10 m, and a joint or
    orientation angle beyond 2 pi rad is a number of degrees read as radians."""
    v = parse_vector(text, lengths + angles, name)
    L = v[:lengths] * (1e-3 if mm else 1.0)
    A = v[lengths:] * (np.pi / 180.0 if deg else 1.0)
    if lengths and np.max(np.abs(L)) > POSE_MAX_LENGTH_M:
        raise typer.BadParameter(f"{name}: {text!r} has a length of {np.max(np.abs(L)):g} m; {name} lengths are in m "
                                 "(give --mm for millimetres)")
    if angles and np.max(np.abs(A)) > 2 * np.pi + 1e-12:
        raise typer.BadParameter(f"{name}: {text!r} has an angle of {np.max(np.abs(A)):g} rad, more than a turn; "
                                 f"{name} angles are in rad (give --deg for degrees)")
    return np.concatenate([L, A])


def select_pose(case, point: str | None, pose: str | None, points=None, labels=POINT_LABELS, *, deg: bool = False,
                mm: bool = False) -> tuple[np.ndarray, str]:
    """The (1, 6) pose (m, rad) from --point P0..P8 or --pose x,y,z,rx,ry,rz (:data:`POSE_UNITS`; rotation
    vector); default P0. ``points`` (k, 6) and ``labels`` (k,): the case's test points when they are not the
    6-PSU's (e.g. a parallel_device case)."""
    if point and pose:
        raise typer.BadParameter("give either --point or --pose, not both")
    if pose:
        return parse_pose(pose, 3, 3, deg=deg, mm=mm)[None, :], f"[{pose}]"
    label = (point or "P0").upper()
    if label not in labels:
        raise typer.BadParameter(f"--point: {point!r}; expected one of {', '.join(labels)}")
    if points is None:
        return test_points(case)[point_index([label])], label
    return np.asarray(points)[[list(labels).index(label)]], label


def direction_vector(direction: str) -> np.ndarray:
    """'+x', '-y', 'z', ... -> unit 3-vector."""
    from femcheck.kinematics.directions import direction_unit
    try:
        return direction_unit(direction)
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None


def load_case_for(path, command: str, kinds=("haptic_6psu",)):
    """Load a case and require one of the case kinds ``command`` works on; else one line naming both."""
    from femcheck.case import load_case
    from femcheck.errors import CaseError

    case = load_case(path)
    kind = case.kind    # a parallel_device case with the 6-PSU's legs runs as "haptic_6psu"
    if kind not in kinds:
        raise CaseError(path, "meta.kind", f"is {kind!r}; `femcheck {command}` takes {' or '.join(map(repr, kinds))} cases")
    return case


#: help text of every ``--json OUT`` option (one meaning across the commands)
JSON_HELP = "write the result as JSON to this file ('-': standard output)"


def emit_json(obj, out: str, inputs=()) -> None:
    """Write ``obj`` as JSON to the path ``out`` (atomically; never over an input) or, for ``-``, print it."""
    import json

    from femcheck.report.atomic import check_output_file, refuse_input_overwrite, write_text_atomic

    text = json.dumps(obj, indent=2, default=float)
    if out == "-":
        typer.echo(text)
        return
    check_output_file(out, "--json")
    refuse_input_overwrite(out, inputs)
    write_text_atomic(out, text + "\n")



def print_directional_stiffness(con, result) -> None:
    """The stiffness along x, y, z of the first pose of a chain result (1 / compliance along the axis), N/mm."""
    kd = [float(result.directional_stiffness(np.eye(3)[a])[0]) for a in range(3)]
    con.print("directional stiffness (1 / compliance along the axis): "
              + ", ".join(f"k_{a} = {v/1e3:.2f} N/mm" for a, v in zip("xyz", kd)))


def print_contributions(con, contrib: dict, title: str) -> None:
    """The table of element shares of the deflection energy, %."""
    from rich.table import Table

    ct = Table(title=title)
    ct.add_column("element")
    ct.add_column("share %", justify="right")
    for name, v in contrib.items():
        ct.add_row(name, f"{100*v:.1f}")
    con.print(ct)
