"""Element parameters of the chain model, derived from a case (all SI).

Every value may be a scalar or a numpy array of shape (n,) broadcasting against the pose axis, so
that a sweep evaluates n (sample, pose) pairs in one vectorized call: pass ``overrides`` =
{dotted case key: (n,) array}. Geometry keys that move joints (radii, angles, lengths) change the
kinematics and are not overridable here: make a case variant with ``case.with_params`` instead.
"""
from __future__ import annotations

import dataclasses

import numpy as np

# the laws are called through their modules (``actuation.cable_stiffness``, ...), so that the function a module
# holds when the parameters are derived is the one used: each law has one implementation, in its module
from femcheck.compliance import actuation, hertz_line_contact, hertz_point_contact, sections
from femcheck.compliance.sections import Section

#: case keys that change the kinematics: they need a case variant, not an array override
KINEMATIC_KEYS = frozenset({
    "geometry.base_radius_m", "geometry.base_pair_half_angle_deg", "geometry.platform_radius_m",
    "geometry.platform_pair_half_angle_deg", "geometry.proximal_link_length_m", "geometry.base_height_m",
    "geometry.rail_length_m", "geometry.min_slider_position_m", "geometry.tcp_offset_m",
    "geometry.platform_pair_rotation_deg", "geometry.guideway_direction", "geometry.platform_rpy_deg",
})


@dataclasses.dataclass(frozen=True)
class DeviceParameters:
    """Scalar ingredients of the five element compliances (arrays broadcast against poses).

    guideway: E_lg, G_lg (Pa), lg_section; proximal link: E_prox, G_prox (Pa), prox_section, L2 (m);
    actuation: c_act (m/N); spherical joint: E_star_sp (Pa), R_star_sp (m), F_min_sp (N);
    universal joint: c_uc = 1/K_UC, c_ub = 1/K_UB (m/N); beam_shear (bool).
    """

    E_lg: np.ndarray | float
    G_lg: np.ndarray | float
    lg_section: Section
    E_prox: np.ndarray | float
    G_prox: np.ndarray | float
    prox_section: Section
    L2: float
    c_act: np.ndarray | float
    E_star_sp: np.ndarray | float
    R_star_sp: np.ndarray | float
    F_min_sp: np.ndarray | float
    c_uc: np.ndarray | float
    c_ub: np.ndarray | float
    beam_shear: bool

    @property
    def n(self) -> int:
        """Length of the array-valued parameters (1 if all scalars)."""
        sizes = [np.size(v) for v in dataclasses.astuple(self) if isinstance(v, np.ndarray)]
        return max(sizes, default=1)


def device_parameters(case, overrides: dict[str, np.ndarray] | None = None) -> DeviceParameters:
    """Derive the element parameters from ``case``; ``overrides`` maps dotted keys to (n,) arrays.

    Material overrides use the material's own keys, e.g. ``"materials.aluminium.E_Pa"``.
    """
    overrides = dict(overrides or {})
    bad = sorted(set(overrides) & KINEMATIC_KEYS)
    if bad:
        raise ValueError(f"{bad[0]}: changes the kinematics; use case.with_params(...) for it")
    used: set[str] = set()

    def get(key: str, value):
        if key in overrides:
            used.add(key)
            return np.asarray(overrides[key], dtype=float)
        return value

    def material(m):
        p = f"materials.{m.name}"
        E, nu = get(f"{p}.E_Pa", m.E_Pa), get(f"{p}.nu", m.nu)
        return E, nu, E / (2.0 * (1.0 + nu))

    # [model.law_scale]: multiply each law's compliance (coverage mutations); beams through 1/E and 1/G (every
    # cantilever term is 1/E or 1/G), Hertz through E*^(-3/2) (k_sp ~ E*^(2/3)), springs directly
    law = case.model.law_scale
    gw, pl, sj, uj, act = case.guideway, case.proximal_link, case.spherical_joint, case.universal_joint, case.actuation
    E_lg, _, G_lg = material(gw.material)
    E_pr, _, G_pr = material(pl.material)
    Eb, nub, _ = material(sj.ball_material)
    Es, nus, _ = material(sj.seat_material)
    Ep, nup, _ = material(uj.pin_material)
    Eo, nuo, _ = material(uj.bore_material)
    k_cable = actuation.cable_stiffness(get("actuation.cable_modulus_Pa", act.cable_modulus_Pa),
                                        get("actuation.cable_diameter_m", act.cable_diameter_m),
                                        get("actuation.cable_length_m", act.cable_length_m))
    k_motor = actuation.motor_stiffness_at_cable(get("actuation.shaft_G_Pa", act.shaft_G_Pa),
                                                 get("actuation.shaft_diameter_m", act.shaft_diameter_m),
                                                 get("actuation.shaft_length_m", act.shaft_length_m),
                                                 get("actuation.capstan_radius_m", act.capstan_radius_m))
    params = DeviceParameters(
        E_lg=E_lg / law.lg, G_lg=G_lg / law.lg,
        lg_section=sections.rectangle_section(get("guideway.width_radial_m", gw.width_radial_m),
                                              get("guideway.depth_tangential_m", gw.depth_tangential_m)),
        E_prox=E_pr / law.prox, G_prox=G_pr / law.prox,
        prox_section=sections.tube_section(get("proximal_link.outer_diameter_m", pl.outer_diameter_m),
                                           get("proximal_link.inner_diameter_m", pl.inner_diameter_m)),
        L2=case.geometry.proximal_link_length_m,
        c_act=(1.0 / k_cable + 1.0 / k_motor) * law.act,
        E_star_sp=hertz_point_contact.effective_modulus(Eb, nub, Es, nus) * law.sp ** -1.5,
        R_star_sp=hertz_point_contact.effective_radius(
            get("spherical_joint.ball_radius_m", sj.ball_radius_m),
            get("spherical_joint.seat_curvature_1_per_m", sj.seat_curvature_1_per_m)),
        F_min_sp=get("spherical_joint.min_contact_force_N", sj.min_contact_force_N),
        c_uc=law.uj / hertz_line_contact.line_contact_stiffness(
            get("universal_joint.contact_length_m", uj.contact_length_m),
            hertz_point_contact.effective_modulus(Ep, nup, Eo, nuo)),
        c_ub=law.uj / hertz_line_contact.pin_bending_stiffness(
            Ep, get("universal_joint.pin_radius_m", uj.pin_radius_m), get("universal_joint.pin_span_m", uj.pin_span_m)),
        beam_shear=case.model.beam_shear,
    )
    unused = sorted(set(overrides) - used)
    if unused:
        raise ValueError(f"{unused[0]}: not a parameter of the chain model (or not overridable); "
                         "numeric keys of [guideway], [proximal_link], [spherical_joint], [universal_joint], "
                         "[actuation] and [materials.NAME] are")
    return params
