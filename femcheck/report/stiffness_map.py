"""Stiffness map over a horizontal workspace slice (seed 000 §4.7, Figs. 20-22).

The directional stiffness ``k_d = 1 / (d^T S_tt d)`` (inverse of the compliance along the unit
direction d, N/m) is evaluated on a grid of TCP positions at height ``nominal_z + z_offset``,
vectorized over the grid; unreachable grid points are left blank. The 50 mm test cube is drawn.
"""
from __future__ import annotations

import dataclasses
import io

import numpy as np

from femcheck.chain import evaluate
from femcheck.kinematics.psu6 import leg_geometry, test_points


@dataclasses.dataclass(frozen=True)
class StiffnessMap:
    """x, y: (nx,), (ny,) grid (m); k: (ny, nx) directional stiffness (N/m, NaN = unreachable)."""

    x: np.ndarray
    y: np.ndarray
    z: float
    k: np.ndarray
    direction: str
    model: str
    joints: str


def slice_poses(case, rotation, z_offset: float, half_width: float, n: int):
    """The map's grid: (x (n,), y (n,) m, z m, poses (n * n, 6) row-major over (y, x)) on an
    n x n square of half-width ``half_width`` (m) centred on the case's nominal TCP, ``z_offset`` (m) above it,
    all at the platform ``rotation`` (3,)."""
    centre = np.asarray(case.workspace.nominal_tcp_m, dtype=float)
    x = centre[0] + np.linspace(-half_width, half_width, n)
    y = centre[1] + np.linspace(-half_width, half_width, n)
    X, Y = np.meshgrid(x, y)
    z = centre[2] + z_offset
    poses = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, z), np.tile(rotation, (X.size, 1))])
    return x, y, z, poses


def stiffness_map(case, direction: str = "x", z_offset: float = 0.025, model: str = "detailed",
                  joints: str | None = None, half_width: float = 0.1, n: int = 81) -> StiffnessMap:
    """Directional stiffness on an n x n grid of half-width ``half_width`` (m) around the cube centre.

    The detailed model is linearized at the case's detailed test load along ``direction``.
    """
    axis = "xyz".index(direction)
    x, y, z, poses = slice_poses(case, test_points(case)[0, 3:], z_offset, half_width, n)
    ok = ~np.isnan(leg_geometry(case, poses, check_reach=False).slider).any(axis=1)
    W = np.zeros(6)
    W[axis] = case.loads.detailed_test_N if model == "detailed" else case.loads.simplified_test_N
    k = np.full(len(poses), np.nan)
    if ok.any():
        r = evaluate(case, poses[ok], W, model=model, joints=joints)
        k[ok] = r.directional_stiffness(np.eye(3)[axis])
        joints = r.joints
    return StiffnessMap(x=x, y=y, z=z, k=k.reshape(len(y), len(x)), direction=direction, model=model,
                        joints=joints or case.model.joint_rotations)


def plot_stiffness_map(case, smap: StiffnessMap) -> bytes:
    """PNG bytes of the map (N/mm, positions in mm) with the test cube's square drawn."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 5.2), dpi=120)
    cs = ax.contourf(smap.x * 1e3, smap.y * 1e3, smap.k / 1e3, levels=20, cmap="viridis")
    fig.colorbar(cs, ax=ax, label=f"k_{smap.direction} (N/mm)")
    c = np.asarray(case.workspace.nominal_tcp_m) * 1e3
    h = case.workspace.cube_edge_m * 1e3 / 2
    ax.plot([c[0] - h, c[0] + h, c[0] + h, c[0] - h, c[0] - h], [c[1] - h, c[1] - h, c[1] + h, c[1] + h, c[1] - h],
            "w-", lw=2, label=f"test cube {2*h:.0f} mm")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_aspect("equal")
    ax.set_title(f"{smap.direction}-stiffness, {smap.model} model, {smap.joints} joints, z = {smap.z*1e3:.0f} mm")
    ax.legend(loc="upper right", fontsize=8, facecolor="0.6", framealpha=0.9)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()
