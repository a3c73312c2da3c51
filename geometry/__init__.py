"""Parametric geometry and meshes of the 6-PSU device's links and passive joints.

Each part builder is ``build(case, size=None, ...) -> PartMesh`` in its own module; :data:`PARTS` maps the
part names of ``femcheck mesh --part`` to them. Meshes are linear tetrahedra with bodies and named
regions (contact master/slave facet sets, clamps, couplings with reference points, load points),
cached on disk by parameters and code version. See docs/fe_solver.md.
"""
from __future__ import annotations

from geometry.errors import MeshingError
from geometry.part_mesh import Body, PartMesh, Region

#: part name -> module path of its builder (imported lazily: no heavy work at import)
PARTS = {
    "guideway": "geometry.guideway",
    "proximal_link": "geometry.proximal_link",
    "spherical_joint": "geometry.spherical_joint",
    "universal_joint": "geometry.universal_joint",
    "platform": "geometry.platform",
    "leg": "geometry.leg",
}


def build_part(case, part: str, size: float | None = None, *, point="P0", chain: int = 0, use_cache: bool = True) -> PartMesh:
    """Mesh ``part`` of ``case`` (target edge length ``size`` m, default from ``[solid.mesh]``).

    ``point``/``chain`` place the guideway length (slider position) and the leg; other parts ignore them.
    Raises :class:`MeshingError` (bad parameters or a failed mesh) or ``ValueError`` for an unknown part.
    """
    import importlib

    if part not in PARTS:
        raise MeshingError(part, {}, f"unknown part; expected one of {', '.join(PARTS)}")
    mod = importlib.import_module(PARTS[part])
    if part == "leg":
        return mod.build(case, point, chain, size, use_cache=use_cache)
    if part == "guideway":
        return mod.build(case, size, point=point, chain=chain, use_cache=use_cache)
    return mod.build(case, size, use_cache=use_cache)


__all__ = ["PARTS", "Body", "MeshingError", "PartMesh", "Region", "build_part"]
