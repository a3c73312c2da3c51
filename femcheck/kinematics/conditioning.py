"""Distance of poses from the singularities of the 6-PSU device (docs/conventions.md §3).

The homogenized velocity Jacobian ``J_h = J diag(I3, I3 / R_p)`` (row i = ``[u_i; (C_i - T) x u_i]^T /
(u_i . e)``) degenerates in two ways:

- a link perpendicular to its rail (``u_i . e -> 0``): the slider cannot push the link, row i blows up
  (actuation singularity, the "horizontal link" case);
- dependent rows (``sigma_min -> 0``): the platform gains a motion the six actuators do not resist
  (constraint singularity).

Both show as ``cond(J_h) = sigma_max / sigma_min -> inf``; the TCP compliance grows with it (a deflection
of tens of mm under 15 N near cond 2000). The reference cube has cond 3.8-4.3. A pose is refused above
``max_condition`` (default :data:`DEFAULT_MAX_CONDITION`) and flagged above ``WARN_FRACTION *
max_condition``. The leg named is the one with the smallest ``|u_i . e|`` when that is what degenerates,
else the leg with the largest share of the left singular vector of ``sigma_min`` (the leg whose actuator
direction the others nearly repeat).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from femcheck.errors import SingularPoseError

#: refuse a pose above this cond(J_h): 250x the reference cube's ~4, where 15 N deflects the TCP by mm
DEFAULT_MAX_CONDITION = 1000.0
#: warn when cond(J_h) exceeds this fraction of the limit
WARN_FRACTION = 0.1
#: |u_i . e| below this counts as an actuation singularity of leg i (link within 0.06 deg of horizontal)
ALIGNMENT_EPS = 1e-3


@dataclasses.dataclass(frozen=True)
class Conditioning:
    """cond (n,) of J_h (inf at a singularity); leg (n,) the leg that degenerates most; alignment (n, 6) |u_i . e|;
    max_condition: the limit used; near (n,) bool above the warning level; singular (n,) bool above the limit."""

    cond: np.ndarray
    leg: np.ndarray
    alignment: np.ndarray
    max_condition: float

    @property
    def singular(self) -> np.ndarray:
        return ~(self.cond <= self.max_condition)

    @property
    def near(self) -> np.ndarray:
        return ~(self.cond <= WARN_FRACTION * self.max_condition) & ~self.singular

    def warnings(self, labels) -> list[str]:
        """One line per pose above the warning level."""
        return [f"pose {labels[k]} is near a singularity: cond(J_h) = {self.cond[k]:.4g} "
                f"(limit {self.max_condition:g}, leg {int(self.leg[k])}); results there are sensitive to the pose"
                for k in np.flatnonzero(self.near)]


def pose_conditioning(case, legs, max_condition: float = DEFAULT_MAX_CONDITION) -> Conditioning:
    """Conditioning of the n poses of ``legs`` (a :class:`~femcheck.kinematics.psu6.LegGeometry`)."""
    if not (np.isfinite(max_condition) and max_condition > 1):
        raise ValueError(f"max_condition = {max_condition}; expected a finite number > 1")
    alignment = np.abs(legs.u @ legs.e)                              # (n, 6)
    r = legs.C - legs.tcp[:, None, :]
    rows = np.concatenate([legs.u, np.cross(r, legs.u) / case.geometry.platform_radius_m], axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        Jh = rows / alignment[..., None]
    finite = np.all(np.isfinite(Jh), axis=(1, 2)) & (alignment.min(axis=1) > ALIGNMENT_EPS)
    cond = np.full(legs.n, np.inf)
    leg = np.argmin(alignment, axis=1)
    if finite.any():
        U, sv, _ = np.linalg.svd(Jh[finite])
        cond[finite] = sv[:, 0] / np.where(sv[:, -1] > 0, sv[:, -1], np.nan)
        cond[finite] = np.where(np.isfinite(cond[finite]), cond[finite], np.inf)
        leg[finite] = np.argmax(np.abs(U[:, :, -1]), axis=1)
    return Conditioning(cond=cond, leg=leg, alignment=alignment, max_condition=float(max_condition))


def require_well_conditioned(case, legs, labels, max_condition: float = DEFAULT_MAX_CONDITION) -> Conditioning:
    """:func:`pose_conditioning`, raising :class:`SingularPoseError` for the first pose above the limit."""
    c = pose_conditioning(case, legs, max_condition)
    bad = np.flatnonzero(c.singular)
    if bad.size:
        k = int(bad[0])
        i = int(c.leg[k])
        detail = f"link {np.degrees(np.arcsin(min(1.0, c.alignment[k, i]))):.3g} deg from perpendicular to its rail" \
            if c.alignment[k, i] < 0.05 else "its actuator direction is nearly repeated by the other legs"
        raise SingularPoseError(str(labels[k]), i, float(c.cond[k]), c.max_condition, detail)
    return c
