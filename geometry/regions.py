"""Named regions of a mesh: boundary facets selected by geometric predicates.

Regions are picked after meshing from the boundary triangles (centroid position and outward normal),
so they follow the parameters automatically. Conventions (docs/fe_solver.md): in a contact pair the
*master* is the stiffer, convex body (steel ball, steel pin) and the *slave* the softer or concave one
(polymer seat, aluminium bore); every facet is oriented with its normal pointing out of its body.
"""
from __future__ import annotations

import numpy as np

from geometry.part_mesh import Region

#: outward faces of a positively oriented tetrahedron (0, 1, 2, 3)
_TET_FACES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])


def boundary_facets(tets: np.ndarray) -> np.ndarray:
    """(k, 3) boundary triangles of a tetrahedral mesh (faces used by exactly one tet), outward oriented
    when the tets are positively oriented. Sorted lexicographically by their sorted node triples."""
    faces = tets[:, _TET_FACES].reshape(-1, 3)
    key = np.sort(faces, axis=1)
    _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    return faces[first[counts == 1]]


def facet_geometry(points: np.ndarray, facets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(centroids (k, 3), unit normals (k, 3), areas (k,)) of triangles (k, 3)."""
    a, b, c = points[facets[:, 0]], points[facets[:, 1]], points[facets[:, 2]]
    n = np.cross(b - a, c - a)
    area2 = np.linalg.norm(n, axis=1)
    return (a + b + c) / 3.0, n / np.where(area2 > 0, area2, 1.0)[:, None], 0.5 * area2


def region(name: str, kind: str, points: np.ndarray, facets: np.ndarray, mask: np.ndarray, *,
           reference_point=None, pair: str = "", side: str = "", doc: str = "") -> Region:
    """A Region of the facets where ``mask`` is true (normals computed from the geometry)."""
    f = facets[np.asarray(mask, bool)]
    _, normals, _ = facet_geometry(points, f)
    return Region(name=name, kind=kind, facets=f, nodes=np.unique(f), normals=normals,
                  reference_point=reference_point, pair=pair, side=side, doc=doc)


def point_region(name: str, points: np.ndarray, where, nodes: np.ndarray | None = None, doc: str = "") -> Region:
    """A load point: the reference point ``where`` (3,) m and the mesh node nearest to it (or ``nodes``)."""
    where = np.asarray(where, float)
    if nodes is None:
        nodes = np.array([int(np.argmin(np.linalg.norm(points - where, axis=1)))])
    return Region(name=name, kind="load", facets=np.zeros((0, 3), int), nodes=nodes, normals=np.zeros((0, 3)),
                  reference_point=where, doc=doc)


def body_facets(tets: np.ndarray, body_of_tet: np.ndarray, body: int) -> np.ndarray:
    """Boundary facets of one body."""
    return boundary_facets(tets[body_of_tet == body])


def opposed_normal_angles_deg(points: np.ndarray, master: Region, slave: Region) -> np.ndarray:
    """For each slave facet, the angle (deg) between its normal and the reversed normal of the nearest
    master facet (by centroid). Two sides of a contact face each other when these are small."""
    cm, _, _ = facet_geometry(points, master.facets)
    cs, _, _ = facet_geometry(points, slave.facets)
    from scipy.spatial import cKDTree

    _, j = cKDTree(cm).query(cs)
    cos = np.einsum("ij,ij->i", slave.normals, -master.normals[j])
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
