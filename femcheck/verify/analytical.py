"""Analytical part of the verification: deflections of both model levels and both joint
idealizations at the 9 test points under the paper's loads (seed 000 §4.1-4.4; docs/conventions.md §8-9).

All numbers come from one vectorized evaluation per (level, joints, direction); tables are in SI
here and converted to mm only by the writers.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.chain import ELEMENT_NAMES, ELEMENTS, evaluate
from femcheck.kinematics.points import PointSet, as_point_set
from femcheck.kinematics.psu6 import POINT_LABELS, condition_number
from femcheck.kinematics.directions import direction_unit

LEVELS = ("simplified", "detailed")
JOINTS = ("rigid", "released")


@dataclasses.dataclass(frozen=True)
class AnalyticalRow:
    """One (point, direction, level, joints) result. Lengths in m, forces in N."""

    point: str
    direction: str
    level: str
    joints: str
    load_N: float
    deflection_m: float          # TCP translation along the load direction
    twist: tuple                 # full TCP twist (m, rad)
    contributions: tuple         # element shares, order ELEMENTS


@dataclasses.dataclass(frozen=True)
class AnalyticalVerification:
    rows: tuple[AnalyticalRow, ...]
    points: tuple[str, ...]
    directions: tuple[str, ...]
    jacobian_condition: np.ndarray     # (n_points,)
    stiffness_condition: dict          # joints -> (n_points,) cond(K_T) homogenized, detailed, worst direction
    sliders_m: np.ndarray              # (n_points, 6)

    def deflection(self, point, direction, level, joints) -> float:
        for r in self.rows:
            if (r.point, r.direction, r.level, r.joints) == (point, direction, level, joints):
                return r.deflection_m
        raise KeyError((point, direction, level, joints))

    def simplified_vs_detailed(self, joints: str) -> dict[tuple[str, str], float]:
        """Relative error |d_simplified - d_detailed| / |d_detailed| per (point, direction), both at the
        detailed test load (the simplified model is linear, so its deflection is scaled; docs/conventions.md §9)."""
        out = {}
        for p in self.points:
            for d in self.directions:
                ds = next(r for r in self.rows if (r.point, r.direction, r.level, r.joints) == (p, d, "simplified", joints))
                dd = next(r for r in self.rows if (r.point, r.direction, r.level, r.joints) == (p, d, "detailed", joints))
                out[(p, d)] = abs(ds.deflection_m / ds.load_N * dd.load_N - dd.deflection_m) / abs(dd.deflection_m)
        return out

    def mean_contributions(self, joints: str) -> dict[str, float]:
        """Unweighted mean element shares over points x directions, detailed model (docs/conventions.md §7)."""
        c = np.array([r.contributions for r in self.rows if r.level == "detailed" and r.joints == joints])
        return {ELEMENT_NAMES[e]: float(v) for e, v in zip(ELEMENTS, c.mean(axis=0))}


def run_analytical(case, points: PointSet | tuple[str, ...] = POINT_LABELS, directions=None) -> AnalyticalVerification:
    """Evaluate both levels and idealizations at ``points`` (a :class:`PointSet`, or labels) under the case's
    test loads, from the point set's one inverse-kinematics pass."""
    directions = tuple(directions or case.loads.directions)
    pts = as_point_set(case, points)
    points, poses, legs = pts.labels, pts.poses, pts.legs
    rows = []
    kcond = {}
    for joints in JOINTS:
        worst = np.zeros(len(points))
        for level in LEVELS:
            load = case.loads.simplified_test_N if level == "simplified" else case.loads.detailed_test_N
            for d in directions:
                u = direction_unit(d)
                W = np.concatenate([load * u, np.zeros(3)])
                r = evaluate(case, poses, W, model=level, joints=joints, labels=list(points), legs=legs)
                for k, p in enumerate(points):
                    rows.append(AnalyticalRow(p, d, level, joints, load, float(r.twist[k, :3] @ u),
                                              tuple(r.twist[k]), tuple(r.contributions[k])))
                if level == "detailed":
                    Kh = r.K.copy()
                    Rp = case.geometry.platform_radius_m
                    Kh[:, :, 3:] /= Rp   # homogenized twist [d; R_p theta]
                    Kh[:, 3:, :] /= Rp
                    worst = np.maximum(worst, np.linalg.cond(Kh))
        kcond[joints] = worst
    return AnalyticalVerification(rows=tuple(rows), points=tuple(points), directions=directions,
                                  jacobian_condition=condition_number(case, legs), stiffness_condition=kcond,
                                  sliders_m=legs.slider)
