"""Test points as data: labels, poses and their inverse kinematics, resolved once and handed on.

A verification run builds one :class:`PointSet` (like Pinocchio's ``model, data, q``) and hands it to the
analytical and the FE side, so both evaluate the same poses from one inverse-kinematics pass and no module
turns labels into poses again.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.kinematics.psu6 import POINT_LABELS, LegGeometry, leg_geometry, test_points


def point_index(labels) -> list[int]:
    """Rows of ``test_points`` for labels such as ("P0", "P7") (the one label lookup; ValueError names a bad one)."""
    bad = [p for p in labels if p not in POINT_LABELS]
    if bad:
        raise ValueError(f"test point {bad[0]!r}; expected one of {', '.join(POINT_LABELS)}")
    return [POINT_LABELS.index(p) for p in labels]


def test_poses(case, labels=None) -> np.ndarray:
    """(n, 6) platform poses [x, y, z, rx, ry, rz] (m, rad) of ``labels`` (default all nine) of ``case``'s test cube,
    for a 6-PSU or a ``parallel_device`` case (the one place labels become poses)."""
    labels = tuple(labels or POINT_LABELS)
    if getattr(case.meta, "kind", None) == "parallel_device":
        from femcheck.parallel.device import test_points as device_points
        return device_points(case)[point_index(labels)]
    return test_points(case)[point_index(labels)]


@dataclasses.dataclass(frozen=True)
class PointSet:
    """n test points: ``labels`` (n,), ``poses`` (n, 6) [x, y, z, rx, ry, rz] (m, rad), ``legs`` their
    inverse kinematics (:class:`~femcheck.kinematics.psu6.LegGeometry`, frame U, SI)."""

    labels: tuple[str, ...]
    poses: np.ndarray
    legs: LegGeometry

    def __len__(self) -> int:
        return len(self.labels)

    def __iter__(self):
        return iter(self.labels)


def point_set(case, labels=None) -> PointSet:
    """The :class:`PointSet` of ``labels`` (default all nine, P0..P8) of ``case``'s test cube (docs/conventions.md §8)."""
    labels = tuple(labels or POINT_LABELS)
    poses = test_poses(case, labels)
    poses.setflags(write=False)
    return PointSet(labels=labels, poses=poses, legs=leg_geometry(case, poses, labels=list(labels)))


def as_point_set(case, points) -> PointSet:
    """``points`` as given (a PointSet) or resolved from labels."""
    return points if isinstance(points, PointSet) else point_set(case, points)
