"""The shell flexibility of a mitred tube corner, as a rotational compliance at the corner of a beam model.

A beam model joins two straight tubes at a sharp corner whose cross-sections stay round and plane: a rigid
corner. A thin-walled tube cut and joined at an angle does not: under bending the sections at the joint
ovalise and the wall bends locally, and the corner turns far more than beam theory says. Piping codes carry
this as a **flexibility factor** k: the bend is k times as flexible in bending as a straight tube of the same
arc length (torsion unchanged). ASME B31.3 (Process Piping), Appendix D, Table D300, "single miter bend or
widely spaced miter bend":

    h = T (1 + cot theta) / (2 r2),   k = 1.52 / h^(5/6) (and k >= 1),   R1 = r2 (1 + cot theta) / 2,

with T the wall thickness, r2 the mean radius of the tube, theta one half of the change of direction (a single
90-degree mitre: theta = 45 deg, h = T / r2, R1 = r2). The table's notes: k applies to bending in any plane,
the factor for torsion is unity, k acts over the bend's effective arc length (R1 times the change of
direction), the data hold for D / T <= 100, and (para. 304.2.3) an offset of 3 degrees or less is no mitre.

In the beam model the straight tubes already run to the corner with beam (k = 1) bending, so the corner gets
the bend's excess: a rotational compliance between the two tube ends meeting there,

    C = (k - 1) / (E I) * R1 * integral_0^alpha (I_3 - t t^T) dphi,   t(phi) = cos(phi) t_in + sin(phi) e_2,

the bending part of a uniform moment along the arc that turns the tangent t from the incoming direction
t_in to the outgoing one t_out by the angle alpha (e_2 the in-plane unit vector normal to t_in toward t_out).
In closed form, with s = sin(2 alpha) / 4 and c = sin^2(alpha) / 2:

    integral t t^T = (alpha/2 + s) t_in t_in^T + (alpha/2 - s) e_2 e_2^T + c (t_in e_2^T + e_2 t_in^T);

for alpha = 90 deg its eigenvalues are pi/2 about the normal of the bend's plane and pi/4 +- 1/2 in the plane.
Translations stay rigid, and the sharp corner's straight legs (2 R1 of tube where the bend has alpha R1) are
kept: the excess over k = 1 is the whole correction.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: B31.3 para. 304.2.3: an angular offset of 3 degrees or less is not a mitre bend
MIN_MITRE_ANGLE_RAD = math.radians(3.0)
#: B31.3 Table D300 note: the factors are demonstrated for D / T <= 100
MAX_D_OVER_T = 100.0


@dataclass(frozen=True)
class MitreFlexibility:
    """B31.3 Table D300 single-mitre data of one corner: ``h`` (flexibility characteristic), ``k`` (flexibility
    factor, >= 1), ``R1_m`` (equivalent bend radius, m), ``angle_rad`` (change of direction alpha = 2 theta)."""

    h: float
    k: float
    R1_m: float
    angle_rad: float

    @property
    def arc_m(self) -> float:
        """Effective arc length over which k acts, m."""
        return self.R1_m * self.angle_rad


def mitre_flexibility(outer_diameter_m: float, wall_m: float, angle_rad: float) -> MitreFlexibility:
    """Single-mitre flexibility (module docstring) of a tube of ``outer_diameter_m`` and ``wall_m`` (m) turned by
    ``angle_rad`` (the change of direction, 3 deg < alpha < 180 deg). ValueError outside the table's range."""
    if not MIN_MITRE_ANGLE_RAD < angle_rad < math.pi:
        raise ValueError(f"mitre angle {math.degrees(angle_rad):.3g} deg; expected 3 < alpha < 180 deg")
    if not 0 < wall_m < outer_diameter_m / 2 or outer_diameter_m / wall_m > MAX_D_OVER_T:
        raise ValueError(f"mitre tube D = {outer_diameter_m} m, T = {wall_m} m; expected D / T <= {MAX_D_OVER_T:g}")
    r2 = (outer_diameter_m - wall_m) / 2
    cot = 1.0 / math.tan(angle_rad / 2)
    h = wall_m * (1 + cot) / (2 * r2)
    return MitreFlexibility(h=h, k=mitre_flexibility_factor(h), R1_m=r2 * (1 + cot) / 2, angle_rad=angle_rad)


def mitre_flexibility_factor(h: float) -> float:
    """B31.3 Table D300's mitre flexibility factor k = 1.52 / h^(5/6), not less than unity (the table's note)."""
    return max(1.0, 1.52 / h ** (5.0 / 6.0))


def bend_bending_integral(t_in, t_out) -> tuple[np.ndarray, float]:
    """(integral over the arc of (I_3 - t t^T) dphi (3, 3), alpha): the closed form of the module docstring for a
    tangent turning from unit ``t_in`` to unit ``t_out`` (base-frame vectors, not parallel)."""
    t_in = np.asarray(t_in, dtype=float) / np.linalg.norm(t_in)
    t_out = np.asarray(t_out, dtype=float) / np.linalg.norm(t_out)
    alpha = math.acos(float(np.clip(t_in @ t_out, -1.0, 1.0)))
    e2 = t_out - (t_in @ t_out) * t_in
    e2 /= np.linalg.norm(e2)
    s, c = math.sin(2 * alpha) / 4, math.sin(alpha) ** 2 / 2
    ttT = (alpha / 2 + s) * np.outer(t_in, t_in) + (alpha / 2 - s) * np.outer(e2, e2) + c * (np.outer(t_in, e2) + np.outer(e2, t_in))
    return alpha * np.eye(3) - ttT, alpha


def corner_compliance(tube, t_in, t_out) -> np.ndarray:
    """(3, 3) rotational compliance, rad/(N m), base frame, that a mitred corner of ``tube`` (a
    :class:`~femcheck.vjm.beam_world.Tube`) adds to the sharp beam corner where the tube's axis turns from
    ``t_in`` to ``t_out`` (module docstring); symmetric, positive semi-definite (zero about the bend's in-plane
    direction only for k = 1)."""
    P, alpha = bend_bending_integral(t_in, t_out)
    m = mitre_flexibility(tube.outer_diameter_m, tube.wall_m, alpha)
    return (m.k - 1.0) * m.R1_m / (tube.E_Pa * tube.section.Ix) * P
