"""Contact tables of a parallel device's passive joints: a ball in its seat (:class:`HertzPoint`) and pins in
bores (:class:`HertzLine`), the inputs of the Hertz laws (``femcheck.compliance``) and of the joints' contact FE.

Kept apart from :mod:`femcheck.case.parallel_device` so that the layout tables of
:mod:`femcheck.case.psu_layout` read them without importing the case kind that offers those tables.
"""

from __future__ import annotations

from dataclasses import dataclass

from femcheck.case.schema import Material, option, quantity


@dataclass(frozen=True)
class HertzPoint:
    """Ball in a seat at an S joint centre (``femcheck.compliance.hertz_point_contact``), linearized at the joint's
    own force under the test wrench (floored at ``min_contact_force_N``)."""
    ball_radius_m: float = quantity("m")
    ball_material: Material = option()
    seat_material: Material = option()
    seat_curvature_1_per_m: float = quantity("1/m", check="any", default=0.0, doc="0 flat; concave seat -1/R_s")
    min_contact_force_N: float = quantity("N", default=1.0)

    def __post_init__(self):
        if 1.0 / self.ball_radius_m + self.seat_curvature_1_per_m <= 0:
            raise ValueError("seat_curvature_1_per_m: 1/R_ball + curvature must be > 0")


@dataclass(frozen=True)
class HertzLine:
    """Pins in bores at an R or U joint (``femcheck.compliance.hertz_line_contact``): line contact in every
    direction, plus pin bending along the adjacent link's axis; load-independent."""
    pin_radius_m: float = quantity("m")
    contact_length_m: float = quantity("m")
    pin_span_m: float = quantity("m")
    pin_material: Material = option()
    bore_material: Material = option()
