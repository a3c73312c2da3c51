"""The parallel-manipulator VJM case (seed 001: the HISS haptic device, an R-CUBE 3-T parallel manipulator).

TOML layout (SI; angles only in keys ending ``_deg``)::

    [meta]        kind = "parallel_vjm", name
    [geometry]    architecture = "r_cube", crank_length_m, coupler_length_m, distal_length_m,
                  platform_edge_m, knee_plane_offset_m, active_limit_deg, crank_axis_offset_m (optional)
    [links.crank], [links.coupler], [links.distal]
                  stiffness = 6 rows of 6 (N/m | N/rad ; N/rad | N m/rad) at the link's distal end, link frame
    [fitting]     weight_map (one index per diagonal entry of W, -1 = fixed at 1), variance_threshold, restarts
    [[test_points]] name, active_deg = [phi_11, phi_21, phi_31]

The leg layout is documented in :mod:`femcheck.vjm.rcube_geometry`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from femcheck.case.schema import CaseMeta as Meta, CaseRecord, Context, build_section, build_sections, option, quantity
from femcheck.vjm.rcube_geometry import RCubeGeometry

CASE_KIND = "parallel_vjm"

Row6 = tuple[float, float, float, float, float, float]


@dataclass(frozen=True)
class Geometry:
    crank_length_m: float = quantity("m", doc="l1")
    coupler_length_m: float = quantity("m", doc="l2")
    distal_length_m: float = quantity("m", doc="l3")
    platform_edge_m: float = quantity("m", doc="d, cube edge; S = l1 + d")
    knee_plane_offset_m: float = quantity("m", doc="h, crank axis below the platform (assumed)")
    active_limit_deg: float = quantity("deg", default=30.0, doc="|phi| limit")
    crank_axis_offset_m: float | None = quantity("m", check="any", default=None,
                                                 doc="c, crank axis at S + c along e_j (assumed; default l1)")
    architecture: Literal["r_cube"] = option("r_cube", doc="leg layout (only the R-CUBE of seed 001)")

    def __post_init__(self):
        if not 0 < self.active_limit_deg < 90:
            raise ValueError(f"active_limit_deg: = {self.active_limit_deg}; expected in (0, 90)")


@dataclass(frozen=True)
class LinkStiffness:
    stiffness: tuple[Row6, Row6, Row6, Row6, Row6, Row6] = quantity("N/m, N/rad, N m/rad", check="any")

    def __post_init__(self):
        K = np.asarray(self.stiffness, dtype=float)
        asym = np.abs(K - K.T).max()
        if asym > 1e-9 * np.abs(K).max():
            i, j = np.unravel_index(np.argmax(np.abs(K - K.T)), K.shape)
            raise ValueError(f"stiffness: not symmetric: [{i}][{j}] = {K[i, j]:g} but [{j}][{i}] = {K[j, i]:g}")
        ev = np.linalg.eigvalsh(K)
        if ev.min() <= 0:
            raise ValueError(f"stiffness: not positive definite (smallest eigenvalue {ev.min():.4g})")


@dataclass(frozen=True)
class Links:
    crank: LinkStiffness = option(doc="link 1")
    coupler: LinkStiffness = option(doc="link 2")
    distal: LinkStiffness = option(doc="link 3")


@dataclass(frozen=True)
class Fitting:
    weight_map: tuple[int, ...] = quantity("-", check="any", default=(-1, 0, 0, 1, 2, 2, -1, 3, 4, 5, 6, 7, -1, 8, 8, 9, 10, 10),
                                           doc="seed 001 eq. 12")
    variance_threshold: float = quantity("-", default=0.1, doc="seed 001 sec. 5.1")
    restarts: int = quantity("-", default=8)
    top: int = quantity("-", default=5, doc="best runs used for the variance")
    stiffness_scaling: Literal["linear", "quadratic"] = option(
        "linear", doc="eq. 10 read as K'_jj = w K_jj (linear, the reading under which the three Table 2 columns "
                      "predict the same device) or K'_jj = w^2 K_jj (quadratic, K' = W K W^T as printed)")
    weights: tuple[float, ...] | None = quantity(
        "-", default=None, doc="identified weights W1..Wp (eq. 12): the links' stiffness scaled by them under stiffness_scaling (written by "
                               "identify --extended-case); absent = 1")

    def __post_init__(self):
        if len(self.weight_map) != 18:
            raise ValueError(f"weight_map: has {len(self.weight_map)} entries; expected 18 (3 links x 6)")
        used = sorted({i for i in self.weight_map if i >= 0})
        if any(i < -1 for i in self.weight_map) or used != list(range(len(used))):
            raise ValueError(f"weight_map: indices must be -1 or 0..p-1 without gaps; got {sorted(set(self.weight_map))}")
        if self.weights is not None and len(self.weights) != len(used):
            raise ValueError(f"weights: has {len(self.weights)} entries; expected {len(used)} (one per weight of weight_map)")

    @property
    def n_weights(self) -> int:
        return max(self.weight_map) + 1


@dataclass(frozen=True)
class TestPoint:
    name: str = option(doc="label")
    active_deg: tuple[float, float, float] = quantity("deg", check="any", doc="phi_11, phi_21, phi_31")


@dataclass(frozen=True)
class ParallelVJMCase(CaseRecord):
    """A validated parallel VJM case. Immutable."""

    geometry: Geometry
    links: Links
    fitting: Fitting
    test_points: tuple[TestPoint, ...]

    kind = CASE_KIND

    @property
    def rcube(self) -> RCubeGeometry:
        g = self.geometry
        return RCubeGeometry(l1=g.crank_length_m, l2=g.coupler_length_m, l3=g.distal_length_m, d=g.platform_edge_m,
                             knee_plane_offset_m=g.knee_plane_offset_m, active_limit_rad=float(np.deg2rad(g.active_limit_deg)),
                             crank_axis_offset_m=g.crank_axis_offset_m)

    @property
    def K_theta(self) -> np.ndarray:
        """(18, 18) block-diagonal virtual-joint stiffness of one leg (links 1-3)."""
        L = self.links
        K = np.zeros((18, 18))
        for j, link in enumerate((L.crank, L.coupler, L.distal)):
            K[6 * j:6 * j + 6, 6 * j:6 * j + 6] = np.asarray(link.stiffness, dtype=float)
        if self.fitting.weights is not None:      # the identified weights of a corrected case (seed 001 eq. 10)
            from femcheck.vjm.weight_fitting import scaled_stiffness
            K = scaled_stiffness(K, np.asarray(self.fitting.weights, float), self.fitting.weight_map,
                                 self.fitting.stiffness_scaling)
        return K

    @property
    def test_point_angles_rad(self) -> np.ndarray:
        return np.deg2rad(np.array([tp.active_deg for tp in self.test_points], dtype=float)).reshape(-1, 3)

    def test_point(self, name: str) -> TestPoint:
        for tp in self.test_points:
            if tp.name.lower() == name.lower():
                return tp
        raise KeyError(name)



def build(raw: dict, path) -> ParallelVJMCase:
    """Validate a parsed TOML document into a :class:`ParallelVJMCase` (errors name file and key)."""
    ctx = Context(path)
    parts = build_sections(ctx, raw,
                           {"meta": Meta, "geometry": Geometry, "links": Links, "fitting": Fitting},
                           optional=("meta", "fitting"), also_allowed=("test_points",))
    meta, geom, links, fitting = parts["meta"], parts["geometry"], parts["links"], parts["fitting"]
    tps = raw.get("test_points", [])
    if not isinstance(tps, list):
        raise ctx.error("test_points", "expected [[test_points]] tables")
    points = tuple(build_section(ctx, f"test_points[{i}]", TestPoint, t) for i, t in enumerate(tps))
    lim = geom.active_limit_deg
    for i, tp in enumerate(points):
        bad = [a for a in tp.active_deg if abs(a) > lim]
        if bad:
            raise ctx.error(f"test_points[{i}].active_deg", f"{bad[0]} deg is outside the active range +-{lim} deg")
    return ParallelVJMCase(meta=meta, geometry=geom, links=links, fitting=fitting, test_points=points)
