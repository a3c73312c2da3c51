"""The universal joint's pin as its contact FE finds it, over the pin's bending compliance: what a thinner pin does.

The chain's U joint is linear (seed 000 §4.4.1: Hertz line contact 1/K_UC plus the bending of a simply supported
pin 1/K_UB, K_UB = 48 E I / L^3). A pin in a bore with radial clearance is not: as it bends, its ends tilt in the
bores until they bear on the opposite line of the bore, which clamps them, and the pin stiffens. The load at which
that happens scales with the pin's bending stiffness (∝ r^4), so a thinner pin stiffens inside the test loads
while the case's own pin may not. Scaling the chain's linear law cannot say that; the fitted compliance of a thin
pin then falls with load like a Hertz contact and reads as the ball.

:class:`PinLawTable` holds the contact-FE axial law δ(F) of the case's U joint (:func:`femcheck.fe_device.
joint_laws.measure_joint_law`) for the case's pin and for pins of radius ρ r at the nodes :data:`RADIUS_FACTORS`,
indexed by the pin's bending compliance factor X = ρ^-4 (1 for the case's pin). The extra deflection of the U
joint at axial load F and factor X,

    e(F; X) = δ(F; X) − δ(F; 1),

is interpolated linearly in X between the nodes (pin bending ∝ X) and continued linearly beyond them (below X = 1
along the first segment, above the last node along the last). It is what the FE-anchored reading model
(:class:`femcheck.diagnose.fe_model.FEAnchoredChainModel`) adds to the chain's U joint when a cause moves that
element: the U-joint column of the element scales then *is* X.

Each node costs one contact-FE solve of the joint (1.5-2 min of CPU and up to 3.3 GB on the coarse mesh), cached
on disk by its inputs like every measured law. Limits: axial law only (the stick lateral and rotational stiffness
of a thin pin, and its lower friction moment μ F r_pin, are not carried); interpolation between nodes smears the
load at which a pin in between starts to bear on the opposite line.
"""
from __future__ import annotations

import dataclasses

import numpy as np

#: pin radius factors ρ of the nodes besides the case's own pin (bending compliance factors 2.44, 7.72 and 24.4): a
#: geometric-like spread from a slightly thinner pin to one under half the case's, off the standard dowel sizes next
#: below a Ø2 mm pin (Ø1.5 and Ø1 mm: ρ = 0.75 and 0.5), so that such a pin is interpolated, never looked up
RADIUS_FACTORS = (0.8, 0.6, 0.45)


@dataclasses.dataclass(frozen=True)
class PinLawTable:
    """U-joint axial laws over the pin's bending compliance factor (module doc).

    ``factors`` (k,) ascending, ``factors[0]`` = 1 (the case's pin); ``laws`` (k,) objects with ``approach(F)``
    (m) at axial loads F (N), e.g. :class:`femcheck.fe_device.joint_laws.MeasuredJointLaw`."""

    factors: tuple
    laws: tuple

    def __post_init__(self):
        X = np.asarray(self.factors, float)
        if X.ndim != 1 or X.size < 2 or X[0] != 1.0 or np.any(np.diff(X) <= 0):
            raise ValueError(f"pin law table: factors must start at 1 and increase, got {list(self.factors)}")
        if len(self.laws) != X.size:
            raise ValueError(f"pin law table: {len(self.laws)} laws for {X.size} factors")

    def extra_approach(self, F, X) -> np.ndarray:
        """e(F; X) (m), F (N) and X (-) broadcast together: the U joint's extra axial deflection over the case's
        pin (module doc); 0 at X = 1 for every F."""
        F, X = np.broadcast_arrays(np.abs(np.asarray(F, float)), np.asarray(X, float))
        nodes = np.asarray(self.factors, float)
        base = self.laws[0].approach(F)
        # extra deflection at each node (k, ...), then the segment of X and its linear weight
        E = np.stack([np.zeros_like(F)] + [law.approach(F) - base for law in self.laws[1:]])
        k = np.clip(np.searchsorted(nodes, X, side="right") - 1, 0, nodes.size - 2)
        t = (X - nodes[k]) / (nodes[k + 1] - nodes[k])
        lo = np.take_along_axis(E, k[None], 0)[0]
        hi = np.take_along_axis(E, (k + 1)[None], 0)[0]
        return lo + t * (hi - lo)


def pin_law_table(case, mesh: str = "coarse", radius_factors=RADIUS_FACTORS, progress=None) -> PinLawTable:
    """The :class:`PinLawTable` of ``case``'s U joint: its contact-FE law for the case's pin and for pins of radius
    ρ r, ρ in ``radius_factors`` (each measured once and cached on disk). A joint whose contact FE does not converge
    raises :class:`femcheck.errors.ConvergenceError` naming it."""
    from femcheck.fe_device.joint_laws import measure_joint_law
    rho = sorted({float(x) for x in radius_factors}, reverse=True)
    if not rho or rho[0] >= 1.0 or rho[-1] <= 0.0:
        raise ValueError(f"pin radius factors must lie in (0, 1), got {list(radius_factors)}")
    r = case.universal_joint.pin_radius_m
    laws = [measure_joint_law(case, "universal", mesh)]
    if progress:
        progress("U-joint law, case's pin")
    for x in rho:
        laws.append(measure_joint_law(case.with_params(**{"universal_joint.pin_radius_m": r * x}), "universal", mesh))
        if progress:
            progress(f"U-joint law, pin radius x{x:g}")
    return PinLawTable(tuple([1.0] + [x ** -4 for x in rho]), tuple(laws))


def link_forces(case, pose, force) -> np.ndarray:
    """(m, 6) N: the axial force of each proximal link (+ tension) under the TCP forces ``force`` (m, 3) at ``pose``
    (m, 6), from the released-joint statics J f = W (:mod:`femcheck.fe_device.joint_forces`; each leg a two-force
    member). Poses are resolved once each."""
    from femcheck.kinematics.psu6 import leg_geometry
    pose, force = np.asarray(pose, float), np.asarray(force, float)
    uniq, inv = np.unique(pose, axis=0, return_inverse=True)
    legs = leg_geometry(case, uniq)
    u, C, tcp = legs.u, legs.C, legs.tcp
    J = np.concatenate([u, np.cross(C - tcp[:, None, :], u)], axis=2).transpose(0, 2, 1)   # (p, 6, 6), column = leg
    W = np.zeros((len(pose), 6))
    W[:, :3] = force
    return np.linalg.solve(J[inv.ravel()], W[..., None])[..., 0]
