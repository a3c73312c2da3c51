"""Elastic half-space closed forms used to verify the contact solver (Johnson, Contact Mechanics, 1985).

* Hertz point contact (Johnson §4.2, eqs. 4.22–4.23): a = (3 F R*/(4 E*))^(1/3), δ = a²/R*,
  p0 = 3F/(2π a²), p(r) = p0 sqrt(1 − r²/a²).
* Hertz line contact per unit length P' (Johnson §4.3, eq. 4.43): a = sqrt(4 P' R*/(π E*)), p0 = 2P'/(π a).
* Boussinesq point load F on a half-space (Johnson §3.2, eq. 3.21b), depth ζ ≥ 0 into the body,
  ρ = sqrt(r² + ζ²), G = E/(2(1+ν)):
      u_r = F/(4πG) [ r ζ/ρ³ − (1−2ν) r/(ρ(ρ+ζ)) ],   u_ζ = F/(4πG) [ ζ²/ρ³ + 2(1−ν)/ρ ]
  used as the far-field boundary condition of a truncated half-space (its error against the Hertz
  pressure field is O(a²/ρ²)).
* Axial displacement under the Hertz pressure (into the body, relative to infinity):
      v(ζ) = −∫_ζ^∞ ε_zz dζ',   ε_zz = (σ_z − 2ν σ_r)/E
  with the axis stresses of Johnson eq. 3.45: σ_z = −p0 (1 + ζ²/a²)⁻¹,
  σ_r = −p0 [ (1+ν)(1 − (ζ/a) arctan(a/ζ)) − ½ (1 + ζ²/a²)⁻¹ ]. v(0) = π a p0 (1−ν²)/(2E) is the body's
  share of the Hertz approach. The contact-induced approach of an FE model is extracted as
      δ(d) = approach of the two axis points at depth d + v₁(d) + v₂(d)
  which must not depend on d when the FE model resolves the contact.

SI units: N, m, Pa.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from scipy.integrate import quad


@dataclasses.dataclass(frozen=True)
class HertzPoint:
    """Hertz point-contact closed form: radius a (m), approach delta (m), peak pressure p0 (Pa)."""

    force: float
    a: float
    delta: float
    p0: float


def hertz_point(F: float, E_star: float, R_star: float) -> HertzPoint:
    """Johnson eqs. 4.22–4.23 for force F (N), contact modulus E* (Pa), effective radius R* (m)."""
    a = (3.0 * F * R_star / (4.0 * E_star)) ** (1.0 / 3.0)
    return HertzPoint(force=F, a=a, delta=a * a / R_star, p0=3.0 * F / (2.0 * np.pi * a * a))


def hertz_line(P_per_length: float, E_star: float, R_star: float) -> tuple[float, float]:
    """Line contact (Johnson eq. 4.43): (half-width a (m), peak pressure p0 (Pa)) for P' (N/m)."""
    a = np.sqrt(4.0 * P_per_length * R_star / (np.pi * E_star))
    return float(a), float(2.0 * P_per_length / (np.pi * a))


def boussinesq(F: float, E: float, nu: float, r, depth):
    """Displacements (u_r, u_depth) (m) of a half-space under a point load F (N) into the body.

    r, depth: arrays (m), depth ≥ 0 measured into the body; u_depth positive into the body.
    """
    G = E / (2.0 * (1.0 + nu))
    r = np.asarray(r, dtype=float)
    z = np.asarray(depth, dtype=float)
    rho = np.sqrt(r * r + z * z)
    c = F / (4.0 * np.pi * G)
    u_r = c * (r * z / rho**3 - (1.0 - 2.0 * nu) * r / (rho * (rho + z)))
    u_z = c * (z * z / rho**3 + 2.0 * (1.0 - nu) / rho)
    return u_r, u_z


def hertz_axis_displacement(depth, a: float, p0: float, E: float, nu: float) -> np.ndarray:
    """v(ζ) (m): axial displacement into the body at depth ζ (m) under the Hertz pressure, v(∞) = 0."""

    def eps_zz(t):  # t = ζ / a
        s_z = -1.0 / (1.0 + t * t)
        s_r = -((1.0 + nu) * (1.0 - t * np.arctan2(1.0, t)) - 0.5 / (1.0 + t * t))
        return (s_z - 2.0 * nu * s_r)

    out = []
    for d in np.atleast_1d(np.asarray(depth, dtype=float)):
        val, _ = quad(eps_zz, d / a, np.inf, epsabs=0.0, epsrel=1e-10, limit=400)
        out.append(-val * p0 * a / E)
    return np.asarray(out).reshape(np.shape(depth))
