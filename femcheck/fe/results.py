"""FE results and their VTU output (issue 5 item 7).

:class:`ElasticResult` bundles a solved displacement field with its basis and material; it derives the
vertex displacements (m) and von Mises stress (Pa, per element and averaged to vertices) and writes a
VTU file with meshio. Contact quantities (pressure Pa, status 0 open / 1 stick / 2 slide, gap m) are
attached as extra point data on the mesh vertices when given, and/or written as a separate VTU point
cloud at the slave integration points (:func:`write_point_cloud_vtu`), which is where the penalty
contact of ``femcheck.fe.contact`` evaluates them.

The VTU holds the mesh as linear tetrahedra on the mesh vertices; for P2 fields the vertex values are
the exact nodal values of the quadratic field (midside values are not written). Files are written
atomically (temporary file in the same folder, then rename).
"""
from __future__ import annotations

import dataclasses
import logging
import os
import tempfile
from pathlib import Path

import numpy as np

from femcheck.fe.elasticity import von_mises

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class ElasticResult:
    """A solved linear-elastic field.

    basis: the vector ``skfem`` basis; u (basis.N,) m; E, nu: scalars or per element (n_elements,);
    point_data / cell_data: optional extra fields, {name: (n_vertices, …)} / {name: (n_elements, …)}
    (e.g. ``contact_pressure_Pa``, ``contact_status``).
    """

    basis: object
    u: np.ndarray
    E: object
    nu: object
    point_data: dict = dataclasses.field(default_factory=dict)
    cell_data: dict = dataclasses.field(default_factory=dict)

    @property
    def vertex_displacement(self) -> np.ndarray:
        """(n_vertices, 3) m: displacement at the mesh vertices."""
        return np.asarray(self.u)[self.basis.nodal_dofs].T

    def von_mises_elements(self) -> np.ndarray:
        """(n_elements,) Pa, quadrature mean per element."""
        return von_mises(self.basis, self.u, self.E, self.nu, at="elements")

    def von_mises_nodes(self) -> np.ndarray:
        """(n_vertices,) Pa, volume-weighted average of the surrounding element means."""
        return von_mises(self.basis, self.u, self.E, self.nu, at="nodes")

    def to_meshio(self):
        import meshio

        mesh = self.basis.mesh
        nv, ne = mesh.p.shape[1], mesh.t.shape[1]
        point_data = {"displacement_m": self.vertex_displacement, "von_mises_Pa": self.von_mises_nodes()}
        for k, v in self.point_data.items():
            v = np.asarray(v)
            if v.shape[0] != nv:
                raise ValueError(f"point_data[{k!r}] has {v.shape[0]} rows; the mesh has {nv} vertices")
            point_data[k] = v
        cell_data = {"von_mises_Pa": [self.von_mises_elements()]}
        for k, v in self.cell_data.items():
            v = np.asarray(v)
            if v.shape[0] != ne:
                raise ValueError(f"cell_data[{k!r}] has {v.shape[0]} rows; the mesh has {ne} elements")
            cell_data[k] = [v]
        return meshio.Mesh(mesh.p.T, [("tetra", mesh.t.T)], point_data=point_data, cell_data=cell_data)

    def write_vtu(self, path) -> Path:
        """Write the result to ``path`` (.vtu) atomically; returns the path."""
        return _write_atomic(self.to_meshio(), path)


def write_point_cloud_vtu(path, points, point_data: dict) -> Path:
    """Write a VTU of isolated points (m, 3) m with point data {name: (m, …)} — e.g. contact pressure
    (Pa) and status at the slave integration points. Atomic."""
    import meshio

    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    for k, v in point_data.items():
        if np.asarray(v).shape[0] != pts.shape[0]:
            raise ValueError(f"point_data[{k!r}] has {np.asarray(v).shape[0]} rows for {pts.shape[0]} points")
    cells = [("vertex", np.arange(pts.shape[0]).reshape(-1, 1))]
    return _write_atomic(meshio.Mesh(pts, cells, point_data={k: np.asarray(v) for k, v in point_data.items()}), path)


def _write_atomic(mesh, path) -> Path:
    import meshio

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=".vtu")
    os.close(fd)
    try:
        meshio.write(tmp, mesh, file_format="vtu")
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    log.info("wrote %s", path)
    return path
