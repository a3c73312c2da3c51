"""The inverse-kinematics state of a parallel device's legs at n poses, as both solvers return it (the numpy
reference in :mod:`femcheck.parallel.leg_kinematics` and the compiled path in :mod:`femcheck.parallel.compiled`)."""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.kinematics.frames import twist_shift


@dataclasses.dataclass(frozen=True)
class LegState:
    """One leg at n poses (base frame, SI).

    q (n, nd) joint values (rad, m) from the home pose; ok (n,) reached (residual below TOL and the joints in
    their limits); residual (n,) final |e|;
    C (n, 3) platform attachment; centres (n, m, 3) joint centres; twists (n, nd, 6) unit joint twists at C;
    link_R (n, L, 3, 3) link frames (columns: section x, y and the link axis z); link_length (n, L) m.
    """

    q: np.ndarray
    ok: np.ndarray
    residual: np.ndarray
    C: np.ndarray
    centres: np.ndarray
    twists: np.ndarray
    link_R: np.ndarray
    link_length: np.ndarray


@dataclasses.dataclass(frozen=True)
class DeviceState:
    """Inverse kinematics of every leg at n TCP poses: tcp (n, 3), R (n, 3, 3) platform orientation, legs."""

    poses: np.ndarray
    tcp: np.ndarray
    R: np.ndarray
    legs: tuple[LegState, ...]
    #: leg-major padded arrays of the compiled path (C, centres, twists, link_R, link_length, closed form used)
    packed: tuple | None = dataclasses.field(default=None, repr=False, compare=False)

    @property
    def n(self) -> int:
        return self.poses.shape[0]

    @property
    def ok(self) -> np.ndarray:
        """(n,) every leg reaches the pose."""
        return np.all([s.ok for s in self.legs], axis=0)

    def G(self, i: int) -> np.ndarray:
        """(n, 6, 6) twist at the TCP -> twist at leg i's attachment C_i (rigid platform)."""
        return twist_shift(self.legs[i].C - self.tcp)
