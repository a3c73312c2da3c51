"""Local subdivision: refine the tetrahedra near a point until the local edge length reaches a target.

Uses scikit-fem's adaptive refinement of tetrahedral meshes (``MeshTet.refined(marked)``, conforming
bisection). New boundary nodes land on the midpoints of boundary edges, i.e. on chords; a ``snap``
callback projects boundary nodes back onto the exact surface (a sphere) after every level, so that the
refined contact surface is as accurate as it is fine.
"""
from __future__ import annotations

import logging
from typing import Callable

import numpy as np

from geometry.errors import MeshingError
from geometry.quality import edge_lengths
from geometry.regions import boundary_facets
from geometry.structured import orient_positive

log = logging.getLogger(__name__)

#: scikit-fem's notice when it copies a mesh array to C order (``skfem.mesh.mesh``)
_C_ORDER_NOTICE = "to C_CONTIGUOUS"


class _DropCOrderNotice(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return _C_ORDER_NOTICE not in record.getMessage()


def bisect(points: np.ndarray, tets: np.ndarray, marked: np.ndarray):
    """scikit-fem's conforming adaptive bisection of the tets ``marked``: points (n, 3), tets (m, 4) -> MeshTet.

    Our input arrays are C-contiguous, but ``MeshTet._adaptive`` (scikit-fem 12) builds its result from
    slices of larger work arrays (``p[:, :nv]``, ``t[:, :nt]``), which are not, and the mesh constructor then
    copies them and logs "Transforming over 1000 vertices to C_CONTIGUOUS" at WARNING. That copy is all the
    message reports and nothing femcheck passes can avoid it, so the notice is dropped for this call only
    (a filter on the ``skfem.mesh.mesh`` logger, removed afterwards); every other scikit-fem message passes.
    """
    from skfem import MeshTet

    sk_log = logging.getLogger("skfem.mesh.mesh")
    flt = _DropCOrderNotice()
    sk_log.addFilter(flt)
    try:
        return MeshTet(np.ascontiguousarray(points.T), np.ascontiguousarray(tets.T)).refined(marked)
    finally:
        sk_log.removeFilter(flt)


def refine_near(points: np.ndarray, tets: np.ndarray, centre, h_target: float, radius: float, *, part: str, parameters: dict,
                snap: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None, max_levels: int = 4):
    """Bisect the tets whose centroid lies within ``radius`` (+ one local element size) of ``centre`` until
    their mean edge length is at most 1.25 h_target (or ``max_levels`` levels). Returns (points, tets),
    positively oriented. ``snap(points, boundary_nodes) -> points`` restores curved boundaries."""
    centre = np.asarray(centre, float)
    p, t = points, tets
    for level in range(max_levels):
        cen = p[t].mean(axis=1)
        d = np.linalg.norm(cen - centre, axis=1)
        le = edge_lengths(p, t).mean(axis=1)
        near = d < radius
        if not near.any() or le[near].mean() <= 1.25 * h_target:
            break
        marked = np.flatnonzero(d < radius + le)
        m = bisect(p, t, marked)
        p, t = np.ascontiguousarray(m.p.T), np.ascontiguousarray(m.t.T).astype(np.int64)
        if snap is not None:
            p = snap(p, np.unique(boundary_facets(orient_positive(p, t))))
        t = orient_positive(p, t)
        log.debug("%s: subdivision level %d -> %d tets", part, level + 1, len(t))
    a, b, c, e = (p[t[:, i]] for i in range(4))
    vol = np.einsum("ij,ij->i", np.cross(b - a, c - a), e - a)
    if np.any(vol <= 0):
        raise MeshingError(part, parameters, f"local subdivision left {(vol <= 0).sum()} degenerate tetrahedra")
    return p, t


def refine_to_size(points: np.ndarray, tets: np.ndarray, size: Callable[[np.ndarray], np.ndarray], *, part: str, parameters: dict,
                   snap: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None, max_levels: int = 8):
    """Bisect every tet whose mean edge length exceeds ``size(centroid)`` ((k, 3) -> (k,) m), level by level
    (longest-edge bisection, conforming), until none does or ``max_levels`` levels are done.

    Unlike :func:`refine_near` the test is per tetrahedron, so tets that are already fine enough are left
    alone and the result grades with ``size``. ``snap(points, boundary_nodes) -> points`` restores a curved
    boundary after every level; a snap that would invert a tet, or fold the mesh, raises
    :class:`MeshingError`. Deterministic: the same input gives the same output. Returns (points, tets),
    positively oriented."""
    from geometry.structured import check_covering

    p, t = points, orient_positive(points, tets)
    for level in range(max_levels):
        le = edge_lengths(p, t).mean(axis=1)
        marked = np.flatnonzero(le > size(p[t].mean(axis=1)))
        if not len(marked):
            break
        m = bisect(p, t, marked)
        p, t = np.ascontiguousarray(m.p.T), orient_positive(m.p.T, np.ascontiguousarray(m.t.T).astype(np.int64))
        if snap is not None:
            p = snap(p, np.unique(boundary_facets(t)))
            a, b, c, e = (p[t[:, i]] for i in range(4))
            if np.any(np.einsum("ij,ij->i", np.cross(b - a, c - a), e - a) <= 0):
                raise MeshingError(part, parameters, f"snapping the refined boundary inverted tetrahedra (level {level + 1})")
        log.debug("%s: refinement level %d -> %d tets", part, level + 1, len(t))
    try:
        check_covering(p, t, part)
    except ValueError as exc:
        raise MeshingError(part, parameters, f"local refinement: {exc}") from exc
    return np.ascontiguousarray(p), t
