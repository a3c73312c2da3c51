"""femcheck: keeps compact analytical stiffness models of robot manipulators honest.

Public API (6-PSU haptic device; SI units, poses as (n, 6) [x, y, z, rx, ry, rz] in m and rad with the
rotation as a rotation vector, wrenches [Fx, Fy, Fz, Mx, My, Mz] in N and N m):

>>> import femcheck
>>> case = femcheck.load_case("cases/haptic_6psu.toml")
>>> poses = femcheck.test_points(case)                       # (9, 6): P0 centre, P1..P8 corners
>>> t = femcheck.deflection(case, poses, [15, 0, 0, 0, 0, 0])  # (9, 6) TCP twists [dx, dy, dz, rx, ry, rz]
>>> K = femcheck.stiffness(case, poses, model="detailed", wrench=[15, 0, 0, 0, 0, 0])  # (9, 6, 6)
>>> shares = femcheck.contributions(case, poses, [15, 0, 0, 0, 0, 0])  # {"guideway": (9,), ...}
"""
from __future__ import annotations

import numpy as np

from femcheck.case import load_case
from femcheck.chain import ELEMENT_NAMES, ELEMENTS, ChainAdjustments, ChainResult, evaluate
from femcheck.kinematics.psu6 import test_points

__version__ = "0.1.0"
__all__ = ["load_case", "test_points", "deflection", "stiffness", "contributions", "evaluate",
           "ChainResult", "ChainAdjustments", "__version__"]


def deflection(case, poses, wrench, model: str = "detailed", joints: str | None = None) -> np.ndarray:
    """TCP deflection (n, 6) [dx, dy, dz, rx, ry, rz] (m, rad) under ``wrench`` (6,) or (n, 6) (N, N m).

    ``model``: "simplified" (guideways + proximal links) or "detailed" (+ actuation, spherical and
    universal joints; the Hertz contacts are linearized at this wrench, docs/conventions.md §6).
    ``joints``: "rigid" | "released" | None (the case's ``[model] joint_rotations``).
    """
    return evaluate(case, poses, wrench, model=model, joints=joints).twist


def stiffness(case, poses, model: str = "detailed", wrench=None, joints: str | None = None) -> np.ndarray:
    """Tangent TCP stiffness (n, 6, 6), SI (N/m, N/rad, N m/m, N m/rad), maps twist [d; theta] to wrench [F; M].

    The detailed model is load-dependent through the Hertz contacts, so it is linearized at
    ``wrench`` (None: unloaded, every spherical joint at ``min_contact_force_N``).
    """
    return evaluate(case, poses, wrench, model=model, joints=joints).K


def contributions(case, poses, wrench, model: str = "detailed", joints: str | None = None) -> dict[str, np.ndarray]:
    """Share of each element type in the TCP deflection energy (seed 000 Fig. 23; docs/conventions.md §7).

    ``c_e = sum_i W_C,i^T S_C,e,i W_C,i / (W_T^T t_T)``: non-negative, summing to 1 for every pose.
    Returns {"guideway", "actuation", "spherical_joint", "proximal_link", "universal_joint"} -> (n,) fractions.
    """
    r = evaluate(case, poses, wrench, model=model, joints=joints)
    return {ELEMENT_NAMES[e]: r.contributions[:, j] for j, e in enumerate(ELEMENTS)}
