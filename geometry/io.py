"""Mesh files with meshio: VTU or XDMF with body and region tags, and reading them back.

Layout: one ``tetra`` block (cell data ``body`` = body index, ``region`` = -1) and one ``triangle`` block
holding the facets of every facet region (``body`` = -1, ``region`` = region tag; a facet in two regions
appears twice). Region tag i is the i-th entry of ``regions`` in the sidecar ``FILE.json`` (meshio does not
keep VTU field data), which also holds kinds, pairs, sides, reference points, bodies and parameters,
so a file read back gives the same :class:`PartMesh`.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from femcheck.report.atomic import write_bytes_atomic
from geometry.part_mesh import Body, PartMesh, Region

SUFFIXES = (".vtu", ".xdmf")


def to_meshio(mesh: PartMesh):
    import meshio

    names = list(mesh.regions)
    tri, tag = [], []
    for i, name in enumerate(names):
        r = mesh.regions[name]
        tri.append(r.facets)
        tag.append(np.full(len(r.facets), i))
    tri = np.vstack(tri) if tri else np.zeros((0, 3), int)
    tag = np.concatenate(tag) if tag else np.zeros(0, int)
    meta = {"part": mesh.part, "cache_key": mesh.cache_key,
            "bodies": [[b.name, b.material, b.analytic_volume_m3] for b in mesh.bodies],
            "regions": [{"name": n, "kind": mesh.regions[n].kind, "pair": mesh.regions[n].pair, "side": mesh.regions[n].side,
                         "doc": mesh.regions[n].doc, "nodes": mesh.regions[n].nodes.tolist() if not len(mesh.regions[n].facets) else None,
                         "reference_point": None if mesh.regions[n].reference_point is None else mesh.regions[n].reference_point.tolist()}
                        for n in names],
            "parameters": dict(mesh.parameters)}
    cells = [("tetra", mesh.tets.astype(np.int64)), ("triangle", tri.astype(np.int64))]
    cell_data = {"body": [mesh.body_of_tet.astype(np.int32), np.full(len(tri), -1, np.int32)],
                 "region": [np.full(len(mesh.tets), -1, np.int32), tag.astype(np.int32)]}
    return meshio.Mesh(mesh.points, cells, cell_data=cell_data), meta


def sidecar(path) -> Path:
    """The JSON file next to a mesh file holding region names and metadata: FILE.vtu -> FILE.vtu.json."""
    path = Path(path)
    return path.with_name(path.name + ".json")


def write_mesh(mesh: PartMesh, path) -> Path:
    """Write ``mesh`` to ``path`` (.vtu or .xdmf) and its sidecar ``path.json``; the VTU is written atomically."""
    import meshio
    import tempfile

    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        from femcheck.errors import FemcheckError
        raise FemcheckError(f"{path}: unsupported mesh file type {path.suffix!r}; expected one of {', '.join(SUFFIXES)}")
    m, meta = to_meshio(mesh)
    write_bytes_atomic(sidecar(path), (json.dumps(meta, indent=1, default=float) + "\n").encode())
    if path.suffix.lower() == ".vtu":
        with tempfile.TemporaryDirectory() as td:
            tmp = Path(td) / path.name
            meshio.write(tmp, m, file_format="vtu", binary=True, compression="zlib")
            return write_bytes_atomic(path, tmp.read_bytes())
    try:
        import h5py  # noqa: F401  (meshio's XDMF writer needs it even for inline XML data)
    except ImportError:
        from femcheck.errors import FemcheckError
        raise FemcheckError(f"{path}: XDMF output needs the h5py package, which is not installed; write .vtu instead") from None
    path.parent.mkdir(parents=True, exist_ok=True)
    meshio.write(path, m, file_format="xdmf")  # FILE.xdmf + FILE.h5
    return path


def read_mesh(path) -> PartMesh:
    """Read a file written by :func:`write_mesh` back into a PartMesh (quality is not stored)."""
    import meshio
    from geometry.regions import facet_geometry

    m = meshio.read(path)
    meta = json.loads(sidecar(path).read_text(encoding="utf-8"))
    tets = np.vstack([c.data for c in m.cells if c.type == "tetra"])
    tri_blocks = [i for i, c in enumerate(m.cells) if c.type == "triangle"]
    tri = np.vstack([m.cells[i].data for i in tri_blocks]) if tri_blocks else np.zeros((0, 3), int)
    tag = np.concatenate([np.asarray(m.cell_data["region"][i]) for i in tri_blocks]) if tri_blocks else np.zeros(0, int)
    body = np.concatenate([np.asarray(m.cell_data["body"][i]) for i, c in enumerate(m.cells) if c.type == "tetra"])
    regions = {}
    for i, r in enumerate(meta["regions"]):
        f = tri[tag == i]
        _, normals, _ = facet_geometry(np.asarray(m.points), f)
        nodes = np.unique(f) if len(f) else np.asarray(r["nodes"] or [], int)
        regions[r["name"]] = Region(name=r["name"], kind=r["kind"], facets=f, nodes=nodes, normals=normals,
                                    reference_point=r["reference_point"], pair=r["pair"], side=r["side"], doc=r["doc"])
    return PartMesh(part=meta["part"], points=np.asarray(m.points, float), tets=tets, body_of_tet=body,
                    bodies=tuple(Body(*b) for b in meta["bodies"]), regions=regions, parameters=meta["parameters"],
                    cache_key=meta["cache_key"])
