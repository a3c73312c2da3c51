"""Stiffness map of a parallel device over a horizontal workspace slice (the ``femcheck map`` picture).

The grid is centred on the test cube; a grid point counts as reachable where every leg's inverse
kinematics closes inside its joint limits; the rest is left blank (NaN).
"""
from __future__ import annotations

import numpy as np

from femcheck.parallel.chain_model import evaluate
from femcheck.parallel.device import test_points
from femcheck.parallel.leg_kinematics import solve_legs
from femcheck.report.stiffness_map import StiffnessMap, slice_poses


def stiffness_map(case, direction: str = "x", z_offset: float = 0.025, model: str = "detailed",
                  joints: str | None = None, half_width: float = 0.1, n: int = 81) -> StiffnessMap:
    """Directional stiffness (N/m) on an n x n grid of half-width ``half_width`` (m) around the cube centre, at
    ``z_offset`` (m) above it, linearized at the case's test force along ``direction``."""
    axis = "xyz".index(direction)
    joints = joints or case.model.joint_rotations
    x, y, z, poses = slice_poses(case, test_points(case)[0, 3:], z_offset, half_width, n)
    dev = case.device
    state = solve_legs(dev, poses)
    ok = state.ok
    k = np.full(len(poses), np.nan)
    if ok.any():
        W = np.zeros(6)
        W[axis] = case.loads.test_N
        r = evaluate(dev, poses[ok], W, model=model, joints=joints)
        k[ok] = r.directional_stiffness(np.eye(3)[axis])
    return StiffnessMap(x=x, y=y, z=z, k=k.reshape(len(y), len(x)), direction=direction, model=model,
                        joints=joints)
