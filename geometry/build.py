"""Shared steps of every part builder: assemble bodies, tag regions, check quality, cache.

A builder computes a JSON-able parameter dict from the case (everything the mesh depends on), then
calls :func:`cached_build`; on a cache miss the builder's mesher makes the bodies and
:func:`assemble` stacks them, finds the regions, checks watertightness / orientation / regions and
reports quality. Any failure raises :class:`MeshingError` naming the part and its parameters.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from geometry import cache
from geometry.errors import MeshingError
from geometry.part_mesh import Body, PartMesh, Region
from geometry.quality import part_report
from geometry.regions import boundary_facets

log = logging.getLogger(__name__)

POINT_LABELS = tuple(f"P{k}" for k in range(9))


@dataclass(frozen=True)
class BodyMesh:
    """One body's tetrahedra before assembly: points (n, 3) m, tets (m, 4)."""

    body: Body
    points: np.ndarray
    tets: np.ndarray


def assemble(part: str, params: dict, body_meshes: list[BodyMesh],
             make_regions: Callable[[np.ndarray, dict[str, np.ndarray]], dict[str, Region]]) -> PartMesh:
    """Stack bodies into one PartMesh; ``make_regions(points, facets_by_body)`` returns the regions."""
    pts, tets, bot, off = [], [], [], 0
    for i, bm in enumerate(body_meshes):
        pts.append(bm.points)
        tets.append(bm.tets + off)
        bot.append(np.full(len(bm.tets), i))
        off += len(bm.points)
    points, tets, body_of_tet = np.vstack(pts), np.vstack(tets), np.concatenate(bot)
    facets_by_body = {bm.body.name: boundary_facets(tets[body_of_tet == i]) for i, bm in enumerate(body_meshes)}
    regions = make_regions(points, facets_by_body)
    empty = [k for k, r in regions.items() if len(r.nodes) == 0]
    if empty:
        raise MeshingError(part, params, f"regions {empty} are empty (mesh too coarse for the region size?)")
    bodies = tuple(bm.body for bm in body_meshes)
    quality = part_report(points, tets, body_of_tet, bodies)
    if quality["n_inverted"]:
        raise MeshingError(part, params, f"{quality['n_inverted']} inverted tetrahedra")
    if not quality["watertight"]:
        bad = [n for n, q in quality["bodies"].items() if not q["watertight"]]
        raise MeshingError(part, params, f"bodies {bad} are not watertight")
    return PartMesh(part=part, points=points, tets=tets, body_of_tet=body_of_tet, bodies=bodies, regions=regions,
                    parameters=params, quality=quality)


def cached_build(part: str, params: dict, mesher: Callable[[], PartMesh], use_cache: bool = True) -> PartMesh:
    """Load the mesh for (part, params, code version) from the cache, or mesh it and store it."""
    import dataclasses
    key = cache.cache_key(part, params)
    if use_cache:
        hit = cache.load(key)
        if hit is not None:
            log.info("%s: mesh loaded from cache %s", part, key)
            return hit
    t0 = time.perf_counter()
    mesh = mesher()
    q = dict(mesh.quality)
    q["mesh_time_s"] = round(time.perf_counter() - t0, 4)
    mesh = dataclasses.replace(mesh, cache_key=key, quality=q)
    log.info("%s: meshed %d tets in %.2f s", part, len(mesh.tets), q["mesh_time_s"])
    if use_cache:
        try:
            cache.store(mesh)
        except OSError as exc:  # a read-only folder must not stop meshing
            log.warning("could not write mesh cache: %s", exc)
    return mesh


def point_index(point) -> int:
    """'P0'..'P8' (or 0..8) -> index into femcheck.kinematics.psu6.test_points."""
    if isinstance(point, (int, np.integer)) and 0 <= int(point) <= 8:
        return int(point)
    if isinstance(point, str) and point.upper() in POINT_LABELS:
        return int(point[1:])
    raise ValueError(f"point: got {point!r}; expected one of {', '.join(POINT_LABELS)}")


def leg_at(case, point="P0", chain: int = 0):
    """(A, B, C, u, e, s) of chain ``chain`` at test point ``point`` (femcheck.kinematics.psu6), SI."""
    from femcheck.kinematics.psu6 import leg_geometry, test_points
    k = point_index(point)
    if not 0 <= int(chain) <= 5:
        raise ValueError(f"chain: got {chain!r}; expected 0..5")
    legs = leg_geometry(case, test_points(case)[k:k + 1], labels=[POINT_LABELS[k]])
    i = int(chain)
    return legs.A[i], legs.B[0, i], legs.C[0, i], legs.u[0, i], legs.e, float(legs.slider[0, i])


def check_size(part: str, params: dict, size: float, smallest_feature: float) -> None:
    """A size must be positive, finite and at most 20x the smallest feature (else the part is not resolved)."""
    if not (np.isfinite(size) and size > 0):
        raise MeshingError(part, params, f"size = {size!r} m; expected a positive edge length")
    if size > 20.0 * smallest_feature:
        raise MeshingError(part, params, f"size = {size} m is more than 20x the smallest feature ({smallest_feature} m)")
