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
    """Joint idealization (CONVENTIONS.md §5)."""
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


def select_pose(case, point: str | None, pose: str | None, points=None, labels=POINT_LABELS) -> tuple[np.ndarray, str]:
    """The (1, 6) pose from --point P0..P8 or --pose x,y,z,rx,ry,rz (m, rad); default P0. ``points`` (k, 6) and
    ``labels`` (k,): the case's test points when they are not the 6-PSU's (e.g. a parallel_device case)."""
    if point and pose:
        raise typer.BadParameter("give either --point or --pose, not both")
    if pose:
        return parse_vector(pose, 6, "--pose")[None, :], f"[{pose}]"
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
    kind = case.meta.kind or "haptic_6psu"
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
