"""Parameters that only the solid (FE) model of the 6-PSU device needs: the optional ``[solid]`` table.

The analytical model never reads these. Every field has a documented default so that a case written
for the analytical model alone still builds meshes (geometry package, docs/fe_solver.md). The
analytical idealizations stay explicit and selectable, so their effect can be measured:
``[solid.spherical_joint] seat = "flat"`` is the paper's sphere on a plane (seed 000 Sect. 3.2.2,
Fig. 12); ``"socket"`` is a spherical cup of radius R_ball + clearance with a wall around it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from femcheck.case.schema import option, quantity


@dataclass(frozen=True)
class SolidSphericalJoint:
    """Seat of the spherical joint (the ball radius and materials come from ``[spherical_joint]``)."""

    seat: Literal["flat", "socket"] = option("flat", doc="flat: sphere on a plane (paper); socket: spherical cup")
    seat_radius_m: float = quantity("m", default=0.006, doc="outer radius of the flat seat disk")
    seat_thickness_m: float = quantity("m", default=0.003, doc="seat material below the contact point (flat disk thickness / socket floor)")
    socket_clearance_m: float = quantity("m", check="nonnegative", default=2.0e-5, doc="radial clearance: socket radius - ball radius")
    socket_wall_m: float = quantity("m", default=0.0015, doc="socket wall thickness around the cup (outer radius = R_ball + clearance + wall)")
    socket_depth_m: float = quantity("m", default=0.002, doc="cup depth from the seat top to the cup bottom (<= socket radius)")
    contact_zone_radius_m: float = quantity("m", default=0.001, doc="radius around the nominal contact point meshed fine and tagged as contact (about 3x the Hertz radius at 15 N)")
    link_cap_half_angle_deg: float = quantity("deg", default=30.0, doc="half angle of the ball cap tied to the proximal link (coupling)")
    friction: float = quantity("-", check="nonnegative", default=0.10, doc="Coulomb coefficient ball/seat (steel on UHMWPE, dry about 0.1-0.2)")

    def __post_init__(self):
        if not 0.0 < self.link_cap_half_angle_deg < 90.0:
            raise ValueError(f"link_cap_half_angle_deg: = {self.link_cap_half_angle_deg}; expected in (0, 90)")


@dataclass(frozen=True)
class SolidUniversalJoint:
    """Yokes and pin fit of the universal joint (pin radius, span and contact length from ``[universal_joint]``).

    The cross is two steel pins: pin a1 (fixed in the platform yoke, local x) and pin a2 (link yoke,
    local y), tied rigidly at the hub. Each pin sits in two yoke arms of thickness = contact length l
    whose bores are centred at +-pin_span/2 (so the pin is simply supported over the span L_u).
    """

    pin_clearance_m: float = quantity("m", check="nonnegative", default=1.0e-5, doc="radial clearance: bore radius - pin radius (0 = line-to-line fit)")
    pin_position: Literal["bottom", "centred"] = option("bottom", doc="bottom: cross shifted by the clearance toward the link so both pins touch their bores; centred: uniform gap")
    yoke_wall_m: float = quantity("m", default=0.0015, doc="yoke material around a bore (arm width = 2 (bore radius + wall))")
    yoke_arm_length_m: float = quantity("m", default=0.005, doc="arm length beyond the bore block toward the link / platform (mount face)")
    hub_half_length_m: float = quantity("m", default=0.002, doc="half length of each pin tied rigidly to the cross hub")
    friction: float = quantity("-", check="nonnegative", default=0.15, doc="Coulomb coefficient pin/bore (steel in aluminium, greased about 0.1-0.2)")


@dataclass(frozen=True)
class SolidPlatform:
    """Moving platform plate (rigid in the analytical model)."""

    thickness_m: float = quantity("m", default=0.006, doc="plate thickness")
    margin_m: float = quantity("m", default=0.012, doc="plate radius = platform_radius_m + margin")
    offset_m: float = quantity("m", check="any", default=0.0, doc="z of the plate mid-plane in the platform frame (C_i plane at 0)")
    mount_radius_m: float = quantity("m", default=0.006, doc="radius of the mount patch around each C_i (coupling to a U joint)")
    handle_radius_m: float = quantity("m", default=0.008, doc="radius of the top patch carrying the TCP load")


@dataclass(frozen=True)
class SolidMesh:
    """Mesh sizes (target edge lengths) and contact refinement."""

    guideway_size_m: float = quantity("m", default=0.004, doc="default edge length of the guideway bar")
    proximal_link_size_m: float = quantity("m", default=0.003, doc="default edge length of the link tube (wall gets >= 2 layers)")
    spherical_joint_size_m: float = quantity("m", default=0.001, doc="default edge length of ball and seat away from contact")
    universal_joint_size_m: float = quantity("m", default=0.001, doc="default edge length of pins and yokes away from contact")
    platform_size_m: float = quantity("m", default=0.004, doc="default edge length of the platform plate")
    contact_refinement: float = quantity("-", default=4.0, doc="size / contact size: elements at a contact are this much smaller")
    grading: float = quantity("-", default=0.35, doc="growth of the edge length with distance from the contact, dh/dd")
    refinement: Literal["structured", "sizing_field", "uniform"] = option(
        "structured", doc="contact refinement: structured graded meshes + local subdivision of the ball (default), "
                          "fTetWild sizing field only, or none")
    tetwild_epsilon_rel: float = quantity("-", default=2.0e-4, doc="fTetWild envelope (surface deviation) relative to the bounding-box diagonal")

    def __post_init__(self):
        if self.contact_refinement < 1.0:
            raise ValueError(f"contact_refinement: = {self.contact_refinement}; expected >= 1")


@dataclass(frozen=True)
class SolidModel:
    """Solid-model parameters (``[solid]`` table and its sub-tables; all optional, SI)."""

    spherical_joint: SolidSphericalJoint = option(SolidSphericalJoint(), doc="[solid.spherical_joint]")
    universal_joint: SolidUniversalJoint = option(SolidUniversalJoint(), doc="[solid.universal_joint]")
    platform: SolidPlatform = option(SolidPlatform(), doc="[solid.platform]")
    mesh: SolidMesh = option(SolidMesh(), doc="[solid.mesh]")
