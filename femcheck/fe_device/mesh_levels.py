"""Mesh levels of the device FE model: target edge lengths (m) of the guideway bar and the link tube.

``default`` takes the case's ``[solid.mesh]`` sizes; ``coarse`` doubles and ``fine`` halves them. The
link tube keeps its section mesh (at least 48 nodes around, 2 layers through the wall, geometry
package) at every level; the level changes the element length along the bars and the tube.
"""
from __future__ import annotations

import dataclasses

MESH_LEVELS = ("coarse", "default", "fine")
_FACTOR = {"coarse": 2.0, "default": 1.0, "fine": 0.5, "finer": 0.25}


@dataclasses.dataclass(frozen=True)
class MeshSizes:
    """Target edge lengths (m): ``guideway_m`` of the bar, ``link_m`` of the tube along its axis."""

    level: str
    guideway_m: float
    link_m: float


def mesh_sizes(case, level: str = "default") -> MeshSizes:
    """Sizes of ``level`` ('coarse' | 'default' | 'fine'; 'finer' = a quarter, for convergence studies)."""
    if level not in _FACTOR:
        raise ValueError(f"mesh level = {level!r}; expected one of {', '.join(MESH_LEVELS)}")
    f = _FACTOR[level]
    m = case.solid.mesh
    return MeshSizes(level, f * m.guideway_size_m, f * m.proximal_link_size_m)


# ---- graded contact-FE levels of the passive joints --------------------------------

#: ball in seat: edge of the elements in the Hertz patch = a / JOINT_CONTACT_FRACTION[level] (a = Hertz
#: contact radius at the largest joint load); the bulk keeps the case's joint size at every level
JOINT_CONTACT_FRACTION = {"coarse": 3.0, "default": 4.5, "fine": 6.0}
#: radius of the fine, contact-tagged disc about the nominal contact point, in units of a (the Hertz
#: patch r ≤ a and a margin for the candidate points, femcheck.fe_device.joint_fe.HERTZ_BAND)
JOINT_ZONE_PER_A = 1.3
#: growth of the element size with the distance from that disc (dh/dd)
JOINT_GRADING = 0.5


#: universal joint: graded levels. Every level refines both the contact zone and the bulk: the nodes around
#: pins and bores crowd at the loaded lines by the angular warp A (spacing 1 − A of the uniform one there),
#: and the element length along the pins and through the yoke arms (the pins' bending and their bearing
#: along the bores) is UNIVERSAL_AXIAL_FACTOR x the case's universal_joint_size_m. The in-plane bulk edge
#: is 2 x the case size and the radial edge through the contact surfaces the coarse level's arc, at every
#: level; the hub ends are element levels at every level (the rigid hub ties exactly hub_half_length_m).
UNIVERSAL_GRADED = True
UNIVERSAL_WARP = {"coarse": 0.5, "default": 0.75, "fine": 0.875}
UNIVERSAL_AXIAL_FACTOR = {"coarse": 2.0, "default": 1.4, "fine": 1.0}


@dataclasses.dataclass(frozen=True)
class JointMeshSizes:
    """Mesh of one joint's contact FE at one level (m): ``bulk_m`` edge away from the contact,
    ``contact_m`` edge in the contact zone, ``zone_m`` radius of the fine contact disc, ``grading``
    dh/dd away from it, ``contact_radius_m`` the Hertz radius a the level is scaled on (None: not graded
    on a, the universal joint, whose level scales the whole mesh)."""

    level: str
    bulk_m: float
    contact_m: float
    zone_m: float | None
    grading: float
    contact_radius_m: float | None
    contact_warp: float = 0.0
    #: universal joint: element length along the pins and through the arms (m), radial edge through the
    #: contact surfaces (m), hub ends as element levels
    axial_m: float | None = None
    surface_m: float | None = None
    hub_levels: bool = False


def joint_mesh_sizes(case, joint: str, level: str = "default", max_load_N: float | None = None) -> JointMeshSizes:
    """Sizes of the joint contact FE at ``level`` ('coarse' | 'default' | 'fine').

    spherical: graded on the Hertz radius a(F) of the largest load ``max_load_N`` (default: the most loaded
    joint at P0, femcheck.fe_device.joint_forces.joint_loads): contact edge a / 3, a / 4.5, a / 6 on a disc
    of radius 1.3 a, growing by 0.5 per unit distance from it; bulk = the case's spherical_joint_size_m at
    every level (so the fine level stays affordable; the level spread measures the contact zone).
    universal (``UNIVERSAL_GRADED``): the angles around pins and bores warped toward the loaded top/bottom
    lines (``contact_warp`` A = 0.5, 0.75, 0.875: spacing 1 − A of the uniform n_around one there,
    ``contact_m`` = that arc) and the element length along the pins and through the yoke arms
    ``axial_m`` = 2, 1.4, 1 x the case's universal_joint_size_m (the bulk the levels refine: pin bending and
    bearing along the bores); in-plane bulk ``bulk_m`` = 2 x the case size and radial edge through the
    contact surfaces ``surface_m`` = the coarse arc at every level; the hub ends are element levels
    (``hub_levels``: without them a 2 mm mesh tied the hub over 1.8 mm only, 6–7 % softer);
    ``UNIVERSAL_GRADED = False``: the case's size times 2, 1, 0.5 everywhere (the levels before the
    graded ones)."""
    if level not in _FACTOR or level == "finer":
        raise ValueError(f"mesh level = {level!r}; expected one of {', '.join(MESH_LEVELS)}")
    m = case.solid.mesh
    if joint == "spherical":
        from femcheck.fe_device.joint_friction import joint_friction
        if max_load_N is None:
            from femcheck.fe_device.joint_forces import joint_loads
            max_load_N = max(joint_loads(case, "P0"))
        a = float(joint_friction(case).contact_radius(float(max_load_N)))
        return JointMeshSizes(level, float(m.spherical_joint_size_m), a / JOINT_CONTACT_FRACTION[level],
                              JOINT_ZONE_PER_A * a, JOINT_GRADING, a)
    if UNIVERSAL_GRADED:
        import math

        from geometry.structured import n_around
        size = _FACTOR["coarse"] * float(m.universal_joint_size_m)
        n = n_around(float(case.universal_joint.pin_radius_m), size / float(m.contact_refinement))
        A = UNIVERSAL_WARP[level]
        uniform_arc = 2.0 * math.pi * float(case.universal_joint.pin_radius_m) / n
        return JointMeshSizes(level, size, uniform_arc * (1.0 - A), None, float(m.grading), None, A,
                              axial_m=UNIVERSAL_AXIAL_FACTOR[level] * float(m.universal_joint_size_m),
                              surface_m=uniform_arc * (1.0 - UNIVERSAL_WARP["coarse"]), hub_levels=True)
    size = _FACTOR[level] * float(m.universal_joint_size_m)
    return JointMeshSizes(level, size, size / float(m.contact_refinement), None, float(m.grading), None)
