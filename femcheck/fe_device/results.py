"""Deformed FE models as files: VTU (meshio) of every load case of a point, off-screen PNGs of a few.

The solid fields are recovered from the condensed solution: for a part with reference-node twists
u_ref (in the part frame), the vertex displacements are u = X u_ref (``SuperElement.recovery``), rotated
to U. Detailed-level fields follow the eq. 1 protocol: (state at P_p + P_T) − (state at P_p).
One VTU per test point holds the mesh of the six guideways and six links (world frame U, m, linear
tetrahedra) and one displacement field per (level, joints, direction), named ``u_<level>_<joints>_<dir>``,
and per load case the cell fields ``von_mises_<...>_Pa`` and ``strain_energy_density_<...>_J_m3``
(w = ½ σ:ε) of the linear-tetrahedron interpolation of the vertex displacements (constant strain per
tetrahedron, so a smoothed view of the P2 part solution, not its exact stress), and the point field
``clamp_reaction_<...>_N`` (N, 3): the force the rail clamp exerts on guideway i, from the equilibrium of the
cantilever from A_i to the slider B: F_A = −F_B with (F_B, M_B) = K_lg u_B (exact for any K_lg), shared
equally by the vertices of the clamped face z = 0 of each guideway (so each leg's vertices sum to F_A and all
six to minus the applied force; the traction distribution over the face is not recovered from the condensed
model, and the clamp moment M_A = −(M_B + (B − A) × F_B) is in :func:`clamp_reactions`, not in the VTU,
because meshio's VTU writer drops field data).
"""
from __future__ import annotations

import logging
import os
import tempfile
from pathlib import Path

import numpy as np

from femcheck.fe_device.leg_model import rot12
from femcheck.kinematics.frames import rot6

log = logging.getLogger(__name__)


def _case_nodes(res) -> dict:
    """Leg nodal twists (6, 6) for 'B_g', 'B_l', 'C_l' of a load case, eq. 1 increment for detailed."""
    last = res.states[-1]
    cur = last.legs.interior(last.u_C)
    if len(res.states) == 1:
        return cur
    first = res.states[0]
    pre = first.legs.interior(first.u_C)
    return {k: cur[k] - pre[k] for k in ("B_g", "B_l", "C_l")}


def point_fields(model, point_result):
    """World mesh and displacement fields of one point.

    Returns ``points`` (N, 3) m, ``tets`` (M, 4), ``part`` (M,) 0 = guideway, 1 = link, ``leg`` (M,) chain,
    and ``fields`` {name: (N, 3) m}. Beams (no solid mesh) contribute nothing.
    """
    pts, tets, part, leg, blocks, off = [], [], [], [], [], 0
    link = model.link
    for i in range(6):
        for kind, se, R, origin in ((0, model.guideways[i], model.R_A[i], model.A[i]), (1, link, model.R_B[i], model.B[i])):
            if len(se.vertices) == 0:
                continue
            pts.append(se.vertices @ R.T + origin)
            tets.append(se.tets + off)
            part.append(np.full(len(se.tets), kind))
            leg.append(np.full(len(se.tets), i))
            blocks.append((kind, i, off, len(se.vertices), se, R))
            off += len(se.vertices)
    if not pts:
        return None
    fields = {}
    for (lvl, j, d), res in point_result.cases.items():
        nodes = _case_nodes(res)
        U = np.zeros((off, 3))
        for kind, i, o, nv, se, R in blocks:
            if kind == 0:
                uref = rot6(R).T @ nodes["B_g"][i]
            else:
                uref = rot12(R).T @ np.r_[nodes["B_l"][i], nodes["C_l"][i]]
            U[o:o + nv] = (se.recovery @ uref).reshape(nv, 3) @ R.T
        fields[f"u_{lvl}_{j}_{d}"] = U
    return np.vstack(pts), np.vstack(tets), np.concatenate(part), np.concatenate(leg), fields


def clamp_reactions(model, point_result) -> dict:
    """{"<level>_<joints>_<dir>": (6, 6)}: per leg the rail clamp's force (N) and moment about A_i (N·m) on
    guideway i, frame U, for the load-case increment (module docstring). Σ_i F_A,i = −applied force."""
    out = {}
    for (lvl, j, d), res in point_result.cases.items():
        nodes = _case_nodes(res)
        rows = np.zeros((6, 6))
        for i, g in enumerate(model.guideways):
            R = model.R_A[i]
            w = g.K @ (rot6(R).T @ nodes["B_g"][i])  # (F_B, M_B) in the guideway frame
            F, M = w[:3], w[3:]
            rows[i, :3] = R @ -F
            rows[i, 3:] = R @ -(M + np.cross(g.ref_points[0], F))
        out[f"{lvl}_{j}_{d}"] = rows
    return out


def tet_fields(points, tets, U, E, nu):
    """Constant-strain stress measures of the linear tetrahedra for vertex displacements U (N, 3) m:
    von Mises σ_vM (Pa) and strain-energy density w = ½ σ:ε (J/m³), each (M,); E, nu per tet (M,)."""
    X = points[tets]  # (M, 4, 3)
    D = X[:, 1:] - X[:, :1]  # (M, 3, 3) edge vectors
    dU = U[tets][:, 1:] - U[tets][:, :1]
    grad = np.linalg.solve(D, dU).transpose(0, 2, 1)  # ∂u_i/∂x_j: D G = dU with G_ji = ∂u_i/∂x_j
    eps = 0.5 * (grad + grad.transpose(0, 2, 1))
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    tr = np.trace(eps, axis1=1, axis2=2)
    sig = 2 * mu[:, None, None] * eps + (lam * tr)[:, None, None] * np.eye(3)
    dev = sig - np.trace(sig, axis1=1, axis2=2)[:, None, None] / 3 * np.eye(3)
    vm = np.sqrt(1.5 * np.einsum("mij,mij->m", dev, dev))
    return vm, 0.5 * np.einsum("mij,mij->m", sig, eps)


#: meshio compression of the VTU data blocks
VTU_COMPRESSION = "zlib"


def write_point_vtu(path, model, point_result, materials=None) -> bool:
    """Write the VTU of one point atomically (temporary file + rename). False when there is no solid mesh.

    materials: ((E_guideway, nu_guideway), (E_link, nu_link)) Pa, - for the stress and energy fields
    (omitted when None). Displacements, von Mises stress and strain-energy density are float32 (a viewer's
    precision), the clamp reactions float64 (they must sum to the load; mostly zeros, they cost nothing
    compressed); the data blocks are compressed (:data:`VTU_COMPRESSION`)."""
    import meshio
    got = point_fields(model, point_result)
    if got is None:
        return False
    points, tets, part, leg, fields = got
    cell_data = {"part": [part.astype(np.int32)], "leg": [leg.astype(np.int32)]}
    if materials is not None:
        E = np.where(part == 0, materials[0][0], materials[1][0]).astype(float)
        nu = np.where(part == 0, materials[0][1], materials[1][1]).astype(float)
        for name, U in fields.items():
            vm, w = tet_fields(points, tets, U, E, nu)
            # float32: 7 significant digits is what a viewer shows; halves the file (float64 noise does not compress)
            cell_data[f"von_mises_{name[2:]}_Pa"] = [vm.astype(np.float32)]
            cell_data[f"strain_energy_density_{name[2:]}_J_m3"] = [w.astype(np.float32)]
    point_data = {k: v.astype(np.float32) for k, v in fields.items()}
    clamp_face, off = [], 0  # (leg, vertex indices of the clamped face z = 0 of its guideway)
    link = model.link
    for i in range(6):
        for se in (model.guideways[i], link):
            if len(se.vertices) == 0:
                continue
            if se is model.guideways[i]:
                clamp_face.append((i, off + np.flatnonzero(np.abs(se.vertices[:, 2]) <= 1e-9)))
            off += len(se.vertices)
    for name, rows in clamp_reactions(model, point_result).items():
        r = np.zeros((len(points), 3))
        for i, idx in clamp_face:
            if idx.size:
                r[idx] = rows[i, :3] / idx.size
        point_data[f"clamp_reaction_{name}_N"] = r
    mesh = meshio.Mesh(points, [("tetra", tets)], point_data=point_data, cell_data=cell_data)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".vtu", dir=path.parent)
    os.close(fd)
    try:
        # zlib-compressed binary blocks; lzma is 12 % smaller on a device point but 4x slower to write
        meshio.write(tmp, mesh, file_format="vtu", compression=VTU_COMPRESSION)
        from femcheck.fe.results import normal_file_mode
        os.chmod(tmp, normal_file_mode())  # mkstemp makes 0600; a VTU is shared like any report file
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return True


def deformed_png(model, point_result, field: str, title: str, scale: float | None = None) -> bytes | None:
    """Off-screen picture (PNG bytes) of the deformed model of ``field`` coloured by |u| (mm); the
    displacement is magnified so that the largest one is 15 mm on screen. pyvista first, matplotlib
    (a scatter of the deformed surface nodes) when VTK cannot render."""
    got = point_fields(model, point_result)
    if got is None:
        return None
    points, tets, part, leg, fields = got
    U = fields[field]
    mag = np.linalg.norm(U, axis=1)
    scale = scale or (0.015 / max(mag.max(), 1e-30))
    try:
        import warnings

        from femcheck.report.offscreen import import_pyvista
        pv = import_pyvista()
        pv.OFF_SCREEN = True
        cells = np.hstack([np.full((len(tets), 1), 4), tets]).ravel()
        grid = pv.UnstructuredGrid(cells, np.full(len(tets), 10, dtype=np.uint8), points + scale * U)
        grid.point_data["displacement (mm)"] = mag * 1e3
        ghost = pv.UnstructuredGrid(cells, np.full(len(tets), 10, dtype=np.uint8), points)
        p = pv.Plotter(off_screen=True, window_size=(900, 700))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # pyvista's FutureWarning about extract_surface's default algorithm
            p.add_mesh(ghost.extract_surface(), color="lightgrey", opacity=0.25)
            p.add_mesh(grid.extract_surface(), scalars="displacement (mm)", cmap="viridis")
        p.add_text(f"{title} (x{scale:.0f})", font_size=10)
        p.view_isometric()
        img = p.screenshot(return_img=True)
        p.close()
        import io
        import matplotlib.pyplot as plt
        buf = io.BytesIO()
        plt.imsave(buf, img, format="png")
        return buf.getvalue()
    except Exception as exc:  # VTK without a usable render window
        log.warning("pyvista rendering failed (%s); drawing the deformed nodes with matplotlib", exc)
        import io
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig = plt.figure(figsize=(7, 6), dpi=100)
        ax = fig.add_subplot(projection="3d")
        X = points + scale * U
        sel = slice(None, None, max(1, len(X) // 20000))
        sc = ax.scatter(*X[sel].T, c=mag[sel] * 1e3, s=1)
        fig.colorbar(sc, label="|u| (mm)")
        ax.set_title(f"{title} (x{scale:.0f})")
        buf = io.BytesIO()
        fig.savefig(buf, format="png")
        plt.close(fig)
        return buf.getvalue()
