"""The actuation system as finite elements: motor shaft, capstan, idler and cable strands (seed 000 §4.4.2-4.4.3).

The analytical chain uses eq. 44: a single strand of length l in series with the shaft torsion seen through the
capstan, c_act = l / (E_c A_c) + r² L_r / (G J) (docs/conventions.md §5, "Actuation"). This module builds the same
mechanism from elements, independently of that law, and condenses it to the slider:

* **motor shaft**: one 3D beam element (:mod:`femcheck.fe.beam`, circle of ``shaft_diameter_m``, shear modulus
  ``shaft_G_Pa``, length ``shaft_length_m``) along the capstan axis a; the rotor end is held (the position loop is
  taken as ideal, as in the analytical model), the capstan end keeps only its rotation about a (bearings);
* **capstan** (radius r = ``capstan_radius_m``) and **idler** (same radius, free to turn about a fixed axle):
  rigid levers, a tangent point P of a pulley with centre c turning by φ about a moves by φ a × (P − c);
* **cable strands**: pretensioned truss elements with geometric stiffness (:mod:`femcheck.fe.cable`), axial rigidity
  E_c π d_c² / 4 and tension τ = ``[actuation.fe] cable_pretension_N``.

Layout (``[actuation.fe] layout``), in the rail frame (e along the rail, n = x_A radial, a = e × n), slider at s:

* ``closed_loop`` (the case's ``cable_length_m`` is the free length of a closed loop capstan - slider - idler -
  capstan, as the case file states): the capstan's tangent point P1 sits on the rail axis at z_c, the idler's
  I1 at z_i = rail_length_m + ``idler_above_rail_m``, with z_i − z_c = l / 2 (two runs of l / 2; the wrapped arcs do
  not stretch and are not free length). Strand 1: P1 → slider (l1 = s − z_c); strand 2: slider → I1
  (z_i − s), over the idler, then I2 → P2 (l / 2) on the return run. With the pretension both strands stay taut
  and act in parallel on the slider; the shaft is in series with the pair, so
  c = 1 / (E A (1 / l1 + 1 / l2)) + r² / K_rotor, l2 = l − l1. Since 1 / l1 + 1 / l2 ≥ 4 / l, the cable is at
  least 4× stiffer than eq. 44's single strand of length l.
* ``single_strand``: eq. 44's idealization, one strand of free length l from the capstan to the slider; the
  return side is held at constant force τ (zero stiffness). The elements then reproduce eq. 44 (a check of the
  assembly, tested).

The assembled system has the unknowns z = [u_S (3), φ (capstan), ψ (idler)]; φ and ψ are condensed out
(Schur complement), leaving the 3 × 3 slider stiffness K_S in U. Its axial entry eᵀ K_S e is the actuation spring
of the device FE; its transverse part is the pretension's geometric stiffness τ (1 / l1 + 1 / l2a) (the pulleys
sit on the rigid base, so the strands hold the slider sideways like a string), which the device FE adds to the
guideway's tip stiffness across the rail (:func:`femcheck.fe_device.device_model.actuation_at`).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from femcheck.fe.beam import BeamSection, assemble_beam_stiffness
from femcheck.fe.cable import cable_stiffness, cable_tensions, strand_geometry


@dataclasses.dataclass(frozen=True)
class ActuationStiffness:
    """The condensed actuation of one leg at slider position ``s_m`` (m, along e from A_i).

    ``k_axial`` N/m along the rail; ``K_slider`` (3, 3) N/m in U; ``strand_lengths`` (m) and
    ``strand_names``; ``dT_dF`` (n_strands,) tension change per newton of axial force on the slider (N/N,
    positive = the strand tightens when the slider is pulled along +e); ``tension_N`` τ;
    ``k_shaft_at_cable`` N/m: the shaft torsion seen at the cable, K_rotor / r²."""

    s_m: float
    k_axial: float
    K_slider: np.ndarray
    strand_names: tuple
    strand_lengths: tuple
    dT_dF: np.ndarray
    tension_N: float
    k_shaft_at_cable: float

    @property
    def k_transverse(self) -> float:
        """N/m: the pretension's geometric stiffness across the rail at the slider (isotropic about e)."""
        return float((np.trace(self.K_slider) - self.k_axial) / 2.0)

    def strand_tensions(self, axial_force_N) -> np.ndarray:
        """Strand tensions (n_strands,) N when the slider carries ``axial_force_N`` along +e (linear)."""
        return self.tension_N + self.dT_dF * float(axial_force_N)

    def slack_force_N(self) -> float:
        """Smallest |axial force| that slackens a strand (inf when none can): the linear model's range."""
        lim = [self.tension_N / abs(d) for d in self.dT_dF if abs(d) > 1e-12]
        return min(lim) if lim else math.inf


def _rail_frame(e):
    """(e, n, a): rail direction, a unit normal n (radial-like, horizontal when possible), a = e × n."""
    e = np.asarray(e, dtype=float) / np.linalg.norm(e)
    ref = np.array([1.0, 0.0, 0.0]) if abs(e[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    n = ref - (ref @ e) * e
    n /= np.linalg.norm(n)
    return e, n, np.cross(e, n)


def _lever(a, arm):
    """3 × 1 map φ -> displacement of a point at ``arm`` (3,) from a pulley centre turning by φ about a."""
    return np.cross(a, arm)[:, None]


def leg_actuation(case, s_m: float, e=(0.0, 0.0, 1.0)) -> ActuationStiffness:
    """Assemble and condense the actuation of one leg with the slider at ``s_m`` (m from A_i along ``e``)."""
    act, fe = case.actuation, case.actuation.fe
    e, n, a = _rail_frame(e)
    r, l = act.capstan_radius_m, act.cable_length_m
    EA = act.cable_modulus_Pa * math.pi * act.cable_diameter_m**2 / 4.0
    tau = fe.cable_pretension_N
    s = float(s_m)
    if fe.layout == "closed_loop":
        z_i = case.geometry.rail_length_m + fe.idler_above_rail_m
        z_c = z_i - l / 2.0
    else:
        z_c, z_i = s - l, math.nan
    if not s > z_c or (fe.layout == "closed_loop" and not s < z_i):
        raise ValueError(f"actuation FE: slider at {s:.4f} m outside the cable run ({z_c:.4f}, {z_i:.4f}) m; "
                         f"check [actuation] cable_length_m = {l} and [actuation.fe] idler_above_rail_m")
    # unknowns z = [u_S (0:3), phi (3), psi (4)]; each strand end is a linear map M (3, 5) of z
    nz = 5 if fe.layout == "closed_loop" else 4
    S = s * e
    c = z_c * e - r * n                           # capstan centre; tangent points P1 = c + r n (rail axis), P2 = c - r n
    ends_S = np.zeros((3, nz)); ends_S[:, :3] = np.eye(3)

    def on_pulley(col, arm):
        M = np.zeros((3, nz))
        M[:, col:col + 1] = _lever(a, arm)
        return M

    strands = [("capstan-slider", c + r * n, S, on_pulley(3, r * n), ends_S)]
    if fe.layout == "closed_loop":
        d = z_i * e - r * n                       # idler centre; I1 = d + r n above the slider, I2 = d - r n
        strands += [("slider-idler", S, d + r * n, ends_S, on_pulley(4, r * n)),
                    ("idler-capstan", d - r * n, c - r * n, on_pulley(4, -r * n), on_pulley(3, -r * n))]
    K = np.zeros((nz, nz))
    geo = []
    for name, x1, x2, M1, M2 in strands:
        ev, L = strand_geometry(np.stack([x1, x2]), [[0, 1]])
        Ke = cable_stiffness(ev, L, EA, tau)[0]
        M = np.vstack([M1, M2])
        K += M.T @ Ke @ M
        geo.append((name, ev[0], float(L[0]), M1, M2))
    # motor shaft: beam along a from the held rotor end to the capstan; keep the capstan end's rotation about a
    G = act.shaft_G_Pa
    E = 2.0 * G * 1.3                              # bending of the shaft is held by the bearings; only G J enters
    Kb = assemble_beam_stiffness(np.stack([c - act.shaft_length_m * a, c]), [[0, 1]], E, G,
                                 BeamSection.circle(act.shaft_diameter_m), orientation=n, shear=False).toarray()
    t_cap = np.zeros(12); t_cap[9:12] = a          # capstan node rotation = phi a
    k_shaft = float(t_cap @ Kb @ t_cap)            # G J / L_r about a
    K[3, 3] += k_shaft
    # condense the pulley rotations (Schur complement) onto the slider translations
    Kss, Ksp, Kpp = K[:3, :3], K[:3, 3:], K[3:, 3:]
    K_S = Kss - Ksp @ np.linalg.solve(Kpp, Ksp.T)
    k_axial = float(e @ K_S @ e)
    # strand tension per newton along e: the axial response alone (transverse decoupled: strands are along e)
    z = np.zeros(nz)
    z[:3] = e / k_axial
    z[3:] = -np.linalg.solve(Kpp, Ksp.T @ z[:3])
    dT = np.array([cable_tensions(ev[None], L, EA, 0.0, (M1 @ z)[None], (M2 @ z)[None])[0]
                   for _, ev, L, M1, M2 in geo])
    return ActuationStiffness(s_m=s, k_axial=k_axial, K_slider=K_S, strand_names=tuple(g[0] for g in geo),
                              strand_lengths=tuple(g[2] for g in geo), dT_dF=dT, tension_N=float(tau),
                              k_shaft_at_cable=k_shaft / r**2)


def actuation_springs(case, sliders_m, e=None) -> np.ndarray:
    """Axial actuation springs (n,) N/m of legs with sliders at ``sliders_m`` (n,) m (:func:`leg_actuation`)."""
    return actuation_legs(case, sliders_m, e)[0]


def actuation_legs(case, sliders_m, e=None):
    """(axial springs (n,) N/m, transverse geometric springs (n,) N/m) of legs with sliders at ``sliders_m``."""
    e = case.geometry.guideway_direction if e is None else e
    legs = [leg_actuation(case, s, e) for s in np.atleast_1d(sliders_m)]
    return np.array([g.k_axial for g in legs]), np.array([g.k_transverse for g in legs])
