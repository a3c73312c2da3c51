"""Watertight surface (trimesh primitives, booleans with the manifold3d engine) -> tetrahedra (pytetwild).

Used only where a part asks for it (``refinement = "sizing_field"`` of the spherical joint, kept for
comparison); the default ball is the structured cubed sphere of geometry.structured. The target edge length may
vary in space: a sizing field h(x) is sampled on a background box mesh and handed to fTetWild
(``bg_vertices/bg_tets/bg_values``), so elements are fine (h_contact) at the contact point and grow
linearly with the distance d from it: h(d) = min(h, h_contact + g d) with grading g.

fTetWild's optimizer is not bit-reproducible between runs, and one thread does not make it so: with
``num_threads=1`` and ``OMP_NUM_THREADS=1``, two runs in fresh processes gave 1843 and 1758 nodes (the
1.5 mm ball with its sizing field), and two calls in one process on a uniform 1.5 mm icosphere ball gave
3005 and 3020 nodes. pytetwild has no seed argument and the library links ``std::random_device``.
Without the optimizer the output repeats (up to the vertex order in each tet) but has degenerate tets
(docs/fe_solver.md).
Reproducibility of such bodies therefore comes only from the on-disk cache (geometry.cache) keyed by the
parameters. Structured bodies (geometry.structured) are deterministic without the cache.
"""
from __future__ import annotations

import logging
import os
import tempfile
from typing import Callable

import numpy as np

from geometry.errors import MeshingError
from geometry.structured import box, orient_positive

log = logging.getLogger(__name__)


def union(*meshes):
    """Boolean union of watertight trimesh meshes (manifold3d engine)."""
    import trimesh
    return trimesh.boolean.union(list(meshes), engine="manifold")


def difference(a, *b):
    """Boolean difference a - b1 - b2 ... (manifold3d engine)."""
    import trimesh
    return trimesh.boolean.difference([a, *b], engine="manifold")


def sizing_background(lo: np.ndarray, hi: np.ndarray, h_of_x: Callable[[np.ndarray], np.ndarray], spacing: float):
    """Background mesh for a sizing field: box grid over [lo, hi] (m) -> (points, tets, values)."""
    axes = [np.linspace(lo[k], hi[k], max(2, int(np.ceil((hi[k] - lo[k]) / spacing)) + 1)) for k in range(3)]
    p, t = box(*axes)
    return p, t.astype(np.int32), np.asarray(h_of_x(p), float)


def tetrahedralize(surface, size: float, *, part: str, parameters: dict, sizing: Callable[[np.ndarray], np.ndarray] | None = None,
                   epsilon_rel: float = 2e-4, threads: int = 1):
    """Tetrahedra of the solid bounded by ``surface`` (a watertight trimesh.Trimesh, m).

    size : target edge length (m) where no sizing field applies; sizing : optional h(x) (k, 3) -> (k,) m;
    epsilon_rel : fTetWild envelope, relative to the bounding-box diagonal (surface deviation bound).
    Returns (points (n, 3), tets (m, 4)) positively oriented, unused nodes removed. Raises
    :class:`MeshingError` naming the part if the surface is not watertight or fTetWild fails.
    """
    import pytetwild

    if not surface.is_watertight:
        raise MeshingError(part, parameters, "input surface is not watertight")
    kw = dict(edge_length_abs=float(size), epsilon=float(epsilon_rel), num_threads=int(threads), quiet=True)
    if sizing is not None:
        lo, hi = surface.bounds
        pad = 0.1 * (hi - lo)
        spacing = max(float(np.min(sizing(surface.vertices))), (hi - lo).max() / 40.0)
        bp, bt, bv = sizing_background(lo - pad, hi + pad, sizing, spacing)
        kw.update(bg_vertices=bp, bg_tets=bt, bg_values=bv)
    cwd = os.getcwd()
    try:
        # fTetWild writes __tracked_surface.stl into the working directory: keep it out of the user's folder
        with tempfile.TemporaryDirectory(prefix="femcheck-tetwild-") as td:
            os.chdir(td)
            try:
                p, t = pytetwild.tetrahedralize(np.asarray(surface.vertices, float), np.asarray(surface.faces, np.int32), **kw)
            finally:
                os.chdir(cwd)
    except Exception as exc:  # pragma: no cover - depends on the native library
        raise MeshingError(part, parameters, f"pytetwild failed: {exc}") from exc
    if len(t) == 0:
        raise MeshingError(part, parameters, "pytetwild returned no tetrahedra")
    p, t = compact(np.asarray(p, float), np.asarray(t, np.int64))
    return p, orient_positive(p, t)


def compact(points: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Drop unused nodes; renumber nodes in lexicographic order of their coordinates and sort the tets
    (a canonical numbering, so that equal meshes compare equal)."""
    used = np.unique(tets)
    p = points[used]
    order = np.lexsort((p[:, 2], p[:, 1], p[:, 0]))
    new = np.empty(len(points), np.int64)
    new[used[order]] = np.arange(len(used))
    t = new[tets]
    t = t[np.lexsort(np.sort(t, axis=1).T[::-1])]
    return p[order], t


def snap_to_sphere(points: np.ndarray, nodes: np.ndarray, centre, radius: float) -> np.ndarray:
    """Copy of points with ``nodes`` projected radially onto the sphere (centre, radius): removes the
    fTetWild envelope error from a spherical surface, so contact gaps are exact at the nodes."""
    out = points.copy()
    d = out[nodes] - np.asarray(centre, float)
    out[nodes] = np.asarray(centre, float) + radius * d / np.linalg.norm(d, axis=1)[:, None]
    return out
