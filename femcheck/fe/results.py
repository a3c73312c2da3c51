"""FE results and their VTU output.

:class:`ElasticResult` bundles a solved displacement field with its basis and material; it derives the
vertex displacements (m), von Mises stress (Pa), the strain-energy density w = ½ σ:ε (J/m³; both per
element as the quadrature mean and averaged to vertices) and, when the constrained DOFs are given, the
reaction forces r = K u − f at the supports (N), and writes a VTU file with meshio. Integrated
over the mesh, w gives the strain energy ½ uᵀK u = ½ uᵀf (Clapeyron) exactly, since the quadrature of the
basis integrates the P2 stiffness exactly; the reactions sum to minus the applied load. Contact quantities (pressure Pa, status 0 open / 1 stick / 2 slide, gap m) are
attached as extra point data on the mesh vertices when given, and/or written as a separate VTU point
cloud at the slave integration points (:func:`write_point_cloud_vtu`), which is where the penalty
contact of ``femcheck.fe.contact`` evaluates them.

The VTU holds the mesh as linear tetrahedra on the mesh vertices; for P2 fields the vertex values are
the exact nodal values of the quadratic field (midside values are not written). A P2 reaction at a midside
node is written half to each end vertex of its edge, so the vertex reactions keep the resultant force.
Files are written atomically (temporary file in the same folder, then rename) with the permissions a
plain ``open()`` would give (0666 less the umask), not ``mkstemp``'s 0600.
"""
from __future__ import annotations

import dataclasses
import logging
import os
import tempfile
from pathlib import Path

import numpy as np

from femcheck.fe.elasticity import strain, stress, von_mises

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
    #: (basis.N,) N, r = K u − f on the constrained DOFs and 0 elsewhere; None = not written
    reactions: np.ndarray | None = None

    @staticmethod
    def reaction_forces(K, u, f, fixed_dofs) -> np.ndarray:
        """(N,) N: r = K u − f on ``fixed_dofs`` (the force the supports exert), 0 on free DOFs."""
        r = np.zeros(K.shape[0])
        fixed = np.asarray(fixed_dofs, dtype=np.int64)
        r[fixed] = (K @ np.asarray(u))[fixed] - np.asarray(f)[fixed]
        return r

    def vertex_reactions(self) -> np.ndarray:
        """(n_vertices, 3) N: the reactions lumped to the vertices (a midside node's half to each end)."""
        r = np.asarray(self.reactions)
        out = r[self.basis.nodal_dofs].T.copy()
        edge_dofs = getattr(self.basis, "edge_dofs", None)
        if edge_dofs is not None and np.size(edge_dofs):
            re = 0.5 * r[edge_dofs].T  # (n_edges, 3)
            for end in self.basis.mesh.edges:
                np.add.at(out, end, re)
        return out

    def strain_energy_density_elements(self) -> np.ndarray:
        """(n_elements,) J/m³: quadrature mean of w = ½ σ:ε over each element."""
        w_q = 0.5 * np.einsum("ijep,ijep->ep", stress(self.basis, self.u, self.E, self.nu),
                              np.asarray(strain(self.basis, self.u)))
        wq = self.basis.dx
        return (w_q * wq).sum(axis=1) / wq.sum(axis=1)

    def element_volumes(self) -> np.ndarray:
        """(n_elements,) m³."""
        return self.basis.dx.sum(axis=1)

    def strain_energy(self) -> float:
        """J: ∫ w dV = ½ uᵀ K u."""
        return float(self.strain_energy_density_elements() @ self.element_volumes())

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
        w_e = self.strain_energy_density_elements()
        vol = self.element_volumes()
        t = mesh.t
        num = np.bincount(t.ravel(), weights=np.tile(w_e * vol, t.shape[0]), minlength=nv)
        den = np.bincount(t.ravel(), weights=np.tile(vol, t.shape[0]), minlength=nv)
        point_data = {"displacement_m": self.vertex_displacement, "von_mises_Pa": self.von_mises_nodes(),
                      "strain_energy_density_J_m3": num / np.where(den > 0, den, 1.0)}
        if self.reactions is not None:
            point_data["reaction_force_N"] = self.vertex_reactions()
        for k, v in self.point_data.items():
            v = np.asarray(v)
            if v.shape[0] != nv:
                raise ValueError(f"point_data[{k!r}] has {v.shape[0]} rows; the mesh has {nv} vertices")
            point_data[k] = v
        cell_data = {"von_mises_Pa": [self.von_mises_elements()], "strain_energy_density_J_m3": [w_e]}
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


def normal_file_mode() -> int:
    """0666 less the process umask: what ``open(path, "w")`` creates (mkstemp would leave 0600)."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def _write_atomic(mesh, path) -> Path:
    import meshio

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=".vtu")
    os.close(fd)
    try:
        meshio.write(tmp, mesh, file_format="vtu")
        os.chmod(tmp, normal_file_mode())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    log.info("wrote %s", path)
    return path
