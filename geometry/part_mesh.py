"""The immutable mesh object every part builder returns, and its named regions.

A :class:`PartMesh` holds linear tetrahedra (P1; the FE side makes P2 from them), the bodies they belong
to (one body = one connected solid of one material, e.g. ``ball`` and ``seat``), and named
:class:`Region` objects: contact facet sets (master/slave, outward normals), clamped faces, coupling
faces with their reference points, and load points. Everything is SI (m). Arrays are read-only.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Literal, Mapping

import numpy as np

RegionKind = Literal["contact", "clamp", "coupling", "load"]


def _frozen(a, dtype) -> np.ndarray:
    a = np.array(a, dtype=dtype, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class Region:
    """A named part of the boundary (or a point) of a mesh.

    facets : (k, 3) int, node indices of boundary triangles, ordered so that their normal points out of
        the body; nodes : (j,) int, the sorted nodes of these facets (or the nodes of a point region);
        normals : (k, 3) float, outward unit normals; reference_point : (3,) float m or None (coupling /
        clamp / load reference point, e.g. the ball centre B); pair, side: for contact regions the pair name
        and ``"master"`` or ``"slave"``; doc: one line on what the region is.
    """

    name: str
    kind: RegionKind
    facets: np.ndarray
    nodes: np.ndarray
    normals: np.ndarray
    reference_point: np.ndarray | None = None
    pair: str = ""
    side: str = ""
    doc: str = ""

    def __post_init__(self):
        object.__setattr__(self, "facets", _frozen(np.reshape(self.facets, (-1, 3)), np.int64))
        object.__setattr__(self, "nodes", _frozen(self.nodes, np.int64))
        object.__setattr__(self, "normals", _frozen(np.reshape(self.normals, (-1, 3)), float))
        if self.reference_point is not None:
            object.__setattr__(self, "reference_point", _frozen(self.reference_point, float))

    def shifted(self, offset: int, R: np.ndarray | None = None, t: np.ndarray | None = None, prefix: str = "") -> "Region":
        """The region with node indices + offset, normals rotated by R and the reference point moved (R p + t)."""
        R = np.eye(3) if R is None else np.asarray(R, float)
        t = np.zeros(3) if t is None else np.asarray(t, float)
        ref = None if self.reference_point is None else R @ self.reference_point + t
        return dataclasses.replace(self, name=prefix + self.name, facets=self.facets + offset, nodes=self.nodes + offset,
                                   normals=self.normals @ R.T, reference_point=ref,
                                   pair=(prefix + self.pair) if self.pair else "")


@dataclass(frozen=True)
class Body:
    """One solid of a part: name, material name (from the case) and analytic volume (m^3)."""

    name: str
    material: str
    analytic_volume_m3: float


@dataclass(frozen=True)
class PartMesh:
    """Linear tetrahedral mesh of a part with bodies and named regions (immutable).

    points : (n, 3) float, m; tets : (m, 4) int, positively oriented (P1); body_of_tet : (m,) int index into
    ``bodies``; regions : name -> :class:`Region`; parameters : the case values and options the part was
    built from (JSON-able); quality : the :class:`geometry.quality.QualityReport` (as a dict);
    cache_key : hash of (part, parameters, code version).
    """

    part: str
    points: np.ndarray
    tets: np.ndarray
    body_of_tet: np.ndarray
    bodies: tuple[Body, ...]
    regions: Mapping[str, Region]
    parameters: Mapping[str, object] = field(default_factory=dict)
    quality: Mapping[str, object] = field(default_factory=dict)
    cache_key: str = ""

    def __post_init__(self):
        object.__setattr__(self, "points", _frozen(self.points, float))
        object.__setattr__(self, "tets", _frozen(self.tets, np.int64))
        object.__setattr__(self, "body_of_tet", _frozen(self.body_of_tet, np.int64))
        object.__setattr__(self, "regions", MappingProxyType(dict(self.regions)))
        object.__setattr__(self, "parameters", MappingProxyType(dict(self.parameters)))
        object.__setattr__(self, "quality", MappingProxyType(dict(self.quality)))

    # -- derived ------------------------------------------------------------------------------------
    @property
    def analytic_volume_m3(self) -> float:
        """Sum of the bodies' analytic volumes, m^3 (overlapping bodies of an assembly count twice)."""
        return float(sum(b.analytic_volume_m3 for b in self.bodies))

    def tet_volumes(self) -> np.ndarray:
        """(m,) signed tetrahedron volumes, m^3 (all > 0 for a valid mesh)."""
        return tet_volumes(self.points, self.tets)

    def body_index(self, name: str) -> int:
        for i, b in enumerate(self.bodies):
            if b.name == name:
                return i
        raise KeyError(f"{self.part}: no body {name!r}; bodies: {[b.name for b in self.bodies]}")

    def regions_of_kind(self, kind: str) -> dict[str, Region]:
        return {k: r for k, r in self.regions.items() if r.kind == kind}

    def contact_pairs(self) -> dict[str, tuple[Region, Region]]:
        """pair name -> (master, slave) contact regions."""
        out: dict[str, dict[str, Region]] = {}
        for r in self.regions.values():
            if r.kind == "contact":
                out.setdefault(r.pair, {})[r.side] = r
        return {p: (d["master"], d["slave"]) for p, d in out.items() if "master" in d and "slave" in d}

    # -- conversions --------------------------------------------------------------------------------
    def to_skfem(self):
        """A ``skfem.MeshTet`` with the facet regions as boundaries (facet indices) and bodies as subdomains.

        Facet regions map to skfem facet indices by their sorted node triples; point regions (load points
        without facets) are left out (use ``regions[name].nodes`` / ``reference_point``).
        """
        from skfem import MeshTet

        mesh = MeshTet(np.ascontiguousarray(self.points.T), np.ascontiguousarray(self.tets.T))
        boundaries = {name: self.skfem_facets(mesh, r) for name, r in self.regions.items() if len(r.facets)}
        subdomains = {b.name: np.flatnonzero(self.body_of_tet == i) for i, b in enumerate(self.bodies)}
        return mesh.with_boundaries(boundaries).with_subdomains(subdomains)

    @staticmethod
    def skfem_facets(mesh, region: Region) -> np.ndarray:
        """Indices into ``mesh.facets`` of the region's triangles (raises if one is not a mesh facet)."""
        f = np.sort(np.asarray(mesh.facets.T, dtype=np.int64), axis=1)
        q = np.sort(np.asarray(region.facets, dtype=np.int64), axis=1)
        n = int(max(f.max(), q.max())) + 1
        kf = (f[:, 0] * n + f[:, 1]) * n + f[:, 2]
        kq = (q[:, 0] * n + q[:, 1]) * n + q[:, 2]
        order = np.argsort(kf)
        pos = np.searchsorted(kf, kq, sorter=order)
        pos = np.clip(pos, 0, len(kf) - 1)
        idx = order[pos]
        if not np.array_equal(kf[idx], kq):
            raise ValueError(f"region {region.name}: {int((kf[idx] != kq).sum())} facets are not facets of the mesh")
        return idx

    def transformed(self, R, t, prefix: str = "") -> "PartMesh":
        """The mesh moved rigidly: x -> R x + t (R (3,3) proper rotation, t (3,) m); names get ``prefix``."""
        R, t = np.asarray(R, float), np.asarray(t, float)
        if abs(np.linalg.det(R) - 1.0) > 1e-9:
            raise ValueError("transformed: R must be a proper rotation (det = +1)")
        regions = {prefix + k: r.shifted(0, R, t, prefix) for k, r in self.regions.items()}
        bodies = tuple(dataclasses.replace(b, name=prefix + b.name) for b in self.bodies)
        return dataclasses.replace(self, points=self.points @ R.T + t, regions=regions, bodies=bodies)


def tet_volumes(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """(m,) signed volumes ((b-a) x (c-a)) . (d-a) / 6 of tetrahedra (m, 4) over points (n, 3), m^3."""
    a, b, c, d = (points[tets[:, i]] for i in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


def merge(part: str, meshes: list[PartMesh]) -> tuple:
    """Concatenate meshes (bodies and regions kept, node indices offset) -> (points, tets, body_of_tet,
    bodies, regions). Region and body names must be unique across the inputs."""
    pts, tets, bot, bodies, regions = [], [], [], [], {}
    off, boff = 0, 0
    for m in meshes:
        pts.append(m.points)
        tets.append(m.tets + off)
        bot.append(m.body_of_tet + boff)
        bodies.extend(m.bodies)
        for k, r in m.regions.items():
            if k in regions:
                raise ValueError(f"{part}: duplicate region name {k!r}")
            regions[k] = r.shifted(off)
        off += len(m.points)
        boff += len(m.bodies)
    return np.vstack(pts), np.vstack(tets), np.concatenate(bot), tuple(bodies), regions
