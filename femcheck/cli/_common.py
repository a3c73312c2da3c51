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
    return np.asarray(values)


def select_pose(case, point: str | None, pose: str | None) -> tuple[np.ndarray, str]:
    """The (1, 6) pose from --point P0..P8 or --pose x,y,z,rx,ry,rz (m, rad); default P0."""
    if point and pose:
        raise typer.BadParameter("give either --point or --pose, not both")
    if pose:
        return parse_vector(pose, 6, "--pose")[None, :], f"[{pose}]"
    label = (point or "P0").upper()
    if label not in POINT_LABELS:
        raise typer.BadParameter(f"--point: {point!r}; expected one of {', '.join(POINT_LABELS)}")
    return test_points(case)[point_index([label])], label


def direction_vector(direction: str) -> np.ndarray:
    """'+x', '-y', 'z', ... -> unit 3-vector."""
    from femcheck.kinematics.directions import direction_unit
    try:
        return direction_unit(direction)
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None
