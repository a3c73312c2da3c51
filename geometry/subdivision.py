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


def refine_near(points: np.ndarray, tets: np.ndarray, centre, h_target: float, radius: float, *, part: str, parameters: dict,
                snap: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None, max_levels: int = 4):
    """Bisect the tets whose centroid lies within ``radius`` (+ one local element size) of ``centre`` until
    their mean edge length is at most 1.25 h_target (or ``max_levels`` levels). Returns (points, tets),
    positively oriented. ``snap(points, boundary_nodes) -> points`` restores curved boundaries."""
    from skfem import MeshTet

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
        m = MeshTet(np.ascontiguousarray(p.T), np.ascontiguousarray(t.T)).refined(marked)
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
