"""Off-screen picture of a part with its regions coloured (pyvista/VTK), written as PNG.

Left: the bodies (translucent, element edges) with every facet region in its colour and the reference
points as dots. Right: a section through the contact (plane through the first contact pair's centre,
normal to the view), showing the elements and their grading. Colours: contact master red, slave
blue, clamp black, coupling green, load orange.
"""
from __future__ import annotations

import logging
import os
from pathlib import Path

import numpy as np

from femcheck.report.atomic import write_bytes_atomic
from geometry.part_mesh import PartMesh

log = logging.getLogger(__name__)

KIND_COLOURS = {"clamp": "black", "coupling": "seagreen", "load": "orange"}
SIDE_COLOURS = {"master": "red", "slave": "royalblue"}


def _grid(points, tets):
    from femcheck.report.offscreen import import_pyvista
    pv = import_pyvista()
    cells = np.hstack([np.full((len(tets), 1), 4), tets]).ravel()
    return pv.UnstructuredGrid(cells, np.full(len(tets), 10, np.uint8), points)  # 10 = VTK_TETRA


def _facets(points, facets):
    from femcheck.report.offscreen import import_pyvista
    pv = import_pyvista()
    return pv.PolyData(points, np.hstack([np.full((len(facets), 1), 3), facets]).ravel())


def render(mesh: PartMesh, path, window_size=(1600, 800), section_normal=(0.0, 1.0, 0.0)) -> Path:
    """Write a PNG of ``mesh`` (see module doc) to ``path`` atomically; returns the path."""
    from femcheck.report.offscreen import import_pyvista
    pv = import_pyvista()

    pv.OFF_SCREEN = True
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    grid = _grid(mesh.points, mesh.tets)
    grid.cell_data["body"] = mesh.body_of_tet
    pl = pv.Plotter(off_screen=True, shape=(1, 2), window_size=list(window_size), border=False)
    pl.subplot(0, 0)
    pl.add_text(f"{mesh.part}: {len(mesh.tets)} tets, regions", font_size=10)
    pl.add_mesh(grid.extract_surface(algorithm='dataset_surface'), color="lightgrey", opacity=0.25, show_edges=True, edge_color="grey", line_width=0.3)
    seen = set()
    for name, r in mesh.regions.items():
        colour = SIDE_COLOURS.get(r.side) if r.kind == "contact" else KIND_COLOURS.get(r.kind, "purple")
        label = f"contact {r.side}" if r.kind == "contact" else r.kind
        if len(r.facets):
            pl.add_mesh(_facets(mesh.points, r.facets), color=colour, show_edges=False,
                        label=None if label in seen else label)
            seen.add(label)
        if r.reference_point is not None:
            pl.add_points(r.reference_point[None], color=KIND_COLOURS["load"] if r.kind == "load" else "magenta",
                          point_size=12, render_points_as_spheres=True)
    pl.add_legend(bcolor="white", size=(0.22, 0.22))
    pl.view_isometric()
    pl.subplot(0, 1)
    pairs = mesh.contact_pairs()
    centre = (mesh.points[next(iter(pairs.values()))[0].nodes].mean(axis=0) if pairs else mesh.points.mean(axis=0))
    cut = grid.clip(normal=section_normal, origin=centre, crinkle=True)
    pl.add_text("section through the contact (elements)", font_size=10)
    pl.add_mesh(cut, scalars="body", show_edges=True, edge_color="black", line_width=0.4, cmap="Pastel1", show_scalar_bar=False)
    pl.view_vector(section_normal)
    pl.reset_camera()
    png = pl.screenshot(return_img=True)
    pl.close()
    import io as _io

    from PIL import Image

    buf = _io.BytesIO()
    Image.fromarray(png).save(buf, format="PNG")
    return write_bytes_atomic(path, buf.getvalue())
