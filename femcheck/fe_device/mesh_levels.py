"""Mesh levels of the device FE model: target edge lengths (m) of the guideway bar and the link tube.

``default`` takes the case's ``[solid.mesh]`` sizes; ``coarse`` doubles and ``fine`` halves them. The
link tube keeps its section mesh (at least 48 nodes around, 2 layers through the wall, geometry
package) at every level; the level changes the element length along the bars and the tube.
"""
from __future__ import annotations

import dataclasses

MESH_LEVELS = ("coarse", "default", "fine")
_FACTOR = {"coarse": 2.0, "default": 1.0, "fine": 0.5, "finer": 0.25}


@dataclasses.dataclass(frozen=True)
class MeshSizes:
    """Target edge lengths (m): ``guideway_m`` of the bar, ``link_m`` of the tube along its axis."""

    level: str
    guideway_m: float
    link_m: float


def mesh_sizes(case, level: str = "default") -> MeshSizes:
    """Sizes of ``level`` ('coarse' | 'default' | 'fine'; 'finer' = a quarter, for convergence studies)."""
    if level not in _FACTOR:
        raise ValueError(f"mesh level = {level!r}; expected one of {', '.join(MESH_LEVELS)}")
    f = _FACTOR[level]
    m = case.solid.mesh
    return MeshSizes(level, f * m.guideway_size_m, f * m.proximal_link_size_m)
