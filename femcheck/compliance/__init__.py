"""Compliance elements: one module per element, each a small pure function returning a local 6x6
compliance (wrench -> twist at the element tip, local frame, SI) or its scalar ingredients.

Local frames follow docs/conventions.md §5: every beam has local z as its axis.

Each law has one implementation, in its module; callers (including the compiled chain kernels, through
:mod:`femcheck.compliance.kernel_laws`) read the module attribute when they run, so a law replaced there is the
law every path uses. The FE never calls these functions (:mod:`femcheck.fe_device.contact_scales`).
"""
from femcheck.compliance.actuation import actuation_compliance, cable_stiffness, motor_stiffness_at_cable
from femcheck.compliance.cantilever_beam import cantilever_compliance
from femcheck.compliance.hertz_line_contact import line_contact_stiffness, pin_bending_stiffness, universal_joint_compliance
from femcheck.compliance.hertz_point_contact import (effective_modulus, effective_radius, hertz_force,
                                                     hertz_tangent_stiffness, spherical_joint_compliance)
from femcheck.compliance.sections import Section, rectangle_section, tube_section

__all__ = [
    "Section", "rectangle_section", "tube_section", "cantilever_compliance",
    "effective_modulus", "effective_radius", "hertz_force", "hertz_tangent_stiffness", "spherical_joint_compliance",
    "line_contact_stiffness", "pin_bending_stiffness", "universal_joint_compliance",
    "cable_stiffness", "motor_stiffness_at_cable", "actuation_compliance",
]
