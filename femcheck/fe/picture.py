"""Off-screen pictures of FE results (pyvista).

:func:`render_png` draws a VTU file (or a meshio/pyvista mesh) coloured by one point or cell field,
optionally on the shape deformed by ``displacement_m`` × ``warp`` (a display magnification), and writes a
PNG atomically. Rendering is always off-screen (``pyvista.OFF_SCREEN = True``). When VTK cannot render
on this machine (no OpenGL context), it falls back to a matplotlib scatter of the surface points coloured
by the same field and logs that it did so; the returned :class:`Picture` says which renderer was used.
"""
from __future__ import annotations

import dataclasses
import logging
import os
import tempfile
from pathlib import Path

import numpy as np

from femcheck.report.atomic import write_bytes_atomic

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class Picture:
    """``path`` of the PNG and the ``renderer`` used ("pyvista" or "matplotlib")."""

    path: Path
    renderer: str


def _as_pyvista(source):
    from femcheck.report.offscreen import import_pyvista
    pv = import_pyvista()

    if isinstance(source, (str, Path)):
        return pv.read(str(source))
    if isinstance(source, pv.DataSet):
        return source
    return pv.wrap(source)  # meshio.Mesh


def render_png(source, path, scalars: str = "von_mises_Pa", warp: float = 0.0, title: str | None = None,
               window_size=(1024, 768)) -> Picture:
    """Render ``source`` (VTU path, meshio.Mesh or pyvista mesh) coloured by ``scalars`` to ``path`` (PNG).

    warp: multiply ``displacement_m`` by this factor to draw the deformed shape (0 = undeformed).
    """
    path = Path(path)
    grid = _as_pyvista(source)
    if scalars not in grid.point_data and scalars not in grid.cell_data:
        raise ValueError(f"field {scalars!r} not in the result; available: "
                         f"{sorted(set(grid.point_data) | set(grid.cell_data))}")
    if warp and "displacement_m" in grid.point_data:
        grid = grid.warp_by_vector("displacement_m", factor=warp)
    try:
        png = _render_pyvista(grid, scalars, title, window_size)
        renderer = "pyvista"
    except Exception as exc:  # no OpenGL context etc.
        log.warning("pyvista rendering failed (%s); falling back to a matplotlib picture", exc)
        png = _render_matplotlib(grid, scalars, title)
        renderer = "matplotlib"
    write_bytes_atomic(path, png)
    return Picture(path=path, renderer=renderer)


def _render_pyvista(grid, scalars, title, window_size) -> bytes:
    from femcheck.report.offscreen import import_pyvista
    pv = import_pyvista()

    pv.OFF_SCREEN = True
    plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
    try:
        plotter.add_mesh(grid, scalars=scalars, show_edges=False, cmap="viridis",
                         scalar_bar_args={"title": scalars})
        if title:
            plotter.add_text(title, font_size=10)
        plotter.view_isometric()
        img = plotter.screenshot(return_img=True)
    finally:
        plotter.close()
    return _png_bytes(img)


def _png_bytes(img) -> bytes:
    import matplotlib.image as mpimg

    fd, tmp = tempfile.mkstemp(suffix=".png")
    os.close(fd)
    try:
        mpimg.imsave(tmp, np.asarray(img))
        return Path(tmp).read_bytes()
    finally:
        os.unlink(tmp)


def _render_matplotlib(grid, scalars, title) -> bytes:
    import io

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    surf = grid.extract_surface()
    if scalars in surf.point_data:
        pts, val = np.asarray(surf.points), np.asarray(surf.point_data[scalars])
    else:
        pts, val = np.asarray(surf.cell_centers().points), np.asarray(surf.cell_data[scalars])
    if val.ndim > 1:
        val = np.linalg.norm(val, axis=1)
    fig = plt.figure(figsize=(8, 6))
    ax = fig.add_subplot(projection="3d")
    sc = ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], c=val, s=4, cmap="viridis")
    fig.colorbar(sc, ax=ax, label=scalars)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    if title:
        ax.set_title(title)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    return buf.getvalue()
