"""Joint forces of the 6-PSU under its test load (seed 000 eq. 1, docs/conventions.md §8).

With ideal passive joints every leg is a two-force member, so the TCP wrench W is carried by the leg forces
f (6,) along the link axes u_i:

    J f = W,   J = [u_i ; (C_i − tcp) × u_i]  (6 x 6, column i per leg)

for the preload P_p (5 N) and P_p + P_T (20 N) along each of the case's test directions. The most loaded joint
(largest |f_i| over legs and directions at the test point) sets the joint's two force levels F_5 and F_20 that
the contact FE applies along the joint axis (``check-joints``, the joint mesh levels, the force ladder of the
joint laws).
"""
from __future__ import annotations

import numpy as np

from femcheck.errors import FemcheckError


def leg_forces(case, point: str = "P0") -> np.ndarray:
    """(n_dir, 2, 6) leg forces (N, + = tension along u_i) at the eq. 1 levels (preload, preload + test)
    for each of the case's test directions, from the released-joint statics J f = W (module doc)."""
    from femcheck.kinematics.directions import direction_unit
    from femcheck.kinematics.points import test_poses
    from femcheck.kinematics.psu6 import leg_geometry

    label = point.upper()
    try:
        poses = test_poses(case, [label])
    except ValueError as exc:
        raise FemcheckError(f"--point {point!r}: {exc}") from None
    legs = leg_geometry(case, poses, labels=[label])
    u, C, tcp = legs.u[0], legs.C[0], legs.tcp[0]
    J = np.vstack([u.T, np.cross(C - tcp, u).T])
    L = case.loads
    levels = np.array([L.detailed_preload_N, L.detailed_preload_N + L.detailed_test_N])
    dirs = np.array([direction_unit(d, sign_required=True) for d in L.directions])
    W = np.zeros((len(dirs), 2, 6))
    W[:, :, :3] = levels[None, :, None] * dirs[:, None, :]
    return np.linalg.solve(J[None, None], W[..., None])[..., 0]


def joint_loads(case, point: str = "P0") -> tuple[float, float]:
    """(F_5, F_20) N: the eq. 1 force levels of the most loaded joint (module doc)."""
    f = np.abs(leg_forces(case, point))
    d, leg = np.unravel_index(np.argmax(f[:, 1, :]), (f.shape[0], f.shape[2]))
    return float(f[d, 0, leg]), float(f[d, 1, leg])
