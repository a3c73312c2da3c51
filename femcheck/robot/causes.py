"""The serial cause vocabulary of the self-weight diagnosis.

Each cause is a direction in the flat elastic parameter space of :mod:`femcheck.robot.elastic` (an increment on
the case's nominal springs, so a cause can *add* an element the model lacks, e.g. joint compliance to a rigid
model) and a *place*: the joints (or links) it sits in. A cause is fitted in every placement its units allow and
the placement with the smallest BIC stands for it:

* ``all``: one parameter shared by every eligible joint (or link);
* ``size``: one per ``size`` label of the case (lumped by joint size), when the case labels sizes;
* ``branch``: one per branch (torso, each arm, head), when the tree has several;
* ``joint``: one per joint, pruned by backward elimination (a joint whose parameter is under
  ``T_KEEP`` standard errors, or on its bound, is dropped), so the cause names the joints it sits in.

Ids (contract): ``joint_torsion_compliance``, ``joint_tilt_compliance``, ``gear_clearance``,
``link_bending_compliance``, ``mass_scale``; on prismatic rows: ``prismatic_axial_compliance``,
``stage_tilt_compliance``, ``guide_clearance`` (the guide's play law is in :mod:`femcheck.robot.elastic`).
"""
from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class CauseSpec:
    """``flat``: the slice of the flat elastic vector it moves; ``unit``: ``joint`` (independent joints), ``row``
    (every row's joint, coupled rows included), ``link`` (the link after each row) or ``single``; ``param``: parameter name with unit; ``lower``: bound on the increment, ``nominal``
    (the total may not go below zero) or a number."""

    id: str
    flat: str
    unit: str
    param: str
    lower: object
    physics: str
    rows: str = "any"

    def applies(self, tree) -> np.ndarray:
        """(n,) bool: rows this cause may sit in (or whose link it may bend): ``rows`` is ``revolute``,
        ``prismatic``, ``guided`` (prismatic rows with a stated guide overlap) or ``any``."""
        if self.rows == "revolute":
            return ~tree.prismatic
        if self.rows == "prismatic":
            return tree.prismatic.copy()
        if self.rows == "guided":
            return tree.prismatic & np.isfinite(tree.guide_overlap)
        return np.ones(tree.n_rows, bool)


VOCABULARY: tuple[CauseSpec, ...] = (
    CauseSpec("joint_torsion_compliance", "torsion", "row", "compliance_rad_per_Nm", "nominal",
              "torsion spring of the drive (gear, belt, motor), or of a coupled joint's own transmission in series "
              "with its coupling: dq = c tau", "revolute"),
    CauseSpec("joint_tilt_compliance", "tilt", "row", "compliance_rad_per_Nm", "nominal",
              "two transversal springs per joint (bearings, housing; seed 002): phi = c (M.x, M.y)", "revolute"),
    CauseSpec("gear_clearance", "backlash", "joint", "backlash_rad", 0.0,
              "backlash: the joint settles by b on the flank the gravity torque pushes it to, dq = b tanh(tau/tau_s)",
              "revolute"),
    CauseSpec("link_bending_compliance", "bending", "link", "compliance_per_Nm2", "nominal",
              "Euler-Bernoulli bending of the link after the joint under its tip load, c = 1/(EI)"),
    CauseSpec("mass_scale", "mass_scale", "single", "mass_scale_increment", -1.0,
              "the CAD masses off by a common factor s (needs an elastic element in the model)"),
    CauseSpec("prismatic_axial_compliance", "torsion", "row", "compliance_m_per_N", "nominal",
              "axial spring of a linear axis' drive (screw, belt, rack, hydraulics): dq = c F.z", "prismatic"),
    CauseSpec("stage_tilt_compliance", "tilt", "row", "compliance_rad_per_Nm", "nominal",
              "tilt springs of a linear axis' moving stage at its carriage (guide rails, rollers): "
              "phi = c (M.x, M.y)", "prismatic"),
    CauseSpec("guide_clearance", "guide", "row", "diametral_clearance_m", "nominal",
              "play of a linear guide of diametral clearance delta engaged over L(q) = L0 - q: the stage tilts "
              "by up to delta / L(q) towards its moment (grows as the overlap shrinks)", "guided"),
)

CAUSE_IDS = tuple(c.id for c in VOCABULARY)
#: a per-joint parameter is kept when it is at least this many standard errors from zero
T_KEEP = 3.0


@dataclasses.dataclass(frozen=True)
class Placement:
    """A cause in one placement: ``groups`` (k lists of unit indices), their ``labels`` (k,), ``kind``."""

    spec: CauseSpec
    kind: str
    groups: tuple[tuple[int, ...], ...]
    labels: tuple[str, ...]

    @property
    def n_params(self) -> int:
        return len(self.groups)

    def restricted(self, keep) -> "Placement":
        keep = list(keep)
        return Placement(self.spec, self.kind, tuple(self.groups[i] for i in keep), tuple(self.labels[i] for i in keep))


def candidate_placements(spec: CauseSpec, tree, eligible: np.ndarray) -> list[Placement]:
    """The placements of ``spec`` over its ``eligible`` units (indices into the cause's slice)."""
    if spec.unit == "single":
        return [Placement(spec, "all", ((0,),), ("all",))] if len(eligible) else []
    units = [int(u) for u in eligible]
    if not units:
        return []
    rows = tree.independent[units] if spec.unit == "joint" else np.asarray(units)
    # a cause with a single eligible joint (a robot's only linear axis, say) is named after it
    out = [Placement(spec, "all", (tuple(units),), ("all",) if len(units) > 1 else (tree.names[int(rows[0])],))]
    for kind, labels in (("size", tree.size), ("branch", tree.branch)):
        lab = [labels[r] for r in rows]
        distinct = list(dict.fromkeys(lab))
        if len(distinct) > 1 and all(lab):
            out.append(Placement(spec, kind, tuple(tuple(u for u, l in zip(units, lab) if l == d) for d in distinct),
                                 tuple(distinct)))
    if len(units) > 1:
        out.append(Placement(spec, "joint", tuple((u,) for u in units), tuple(tree.names[r] for r in rows)))
    return out


def place_text(placement: Placement, tree, values: np.ndarray | None = None) -> str:
    """Where the cause sits, in words ('joints 2-4 of right_arm (...)', 'all joints', 'branch left_arm')."""
    spec = placement.spec
    if spec.unit == "single":
        return "the whole robot (every link mass)"
    word = "links after joints" if spec.unit == "link" else "joints"
    if placement.kind == "all" and len(placement.groups[0]) == 1:
        rows = tree.independent[list(placement.groups[0])] if spec.unit == "joint" else np.asarray(placement.groups[0])
        return ("links after " if spec.unit == "link" else "") + tree.joint_place(rows)
    if placement.kind == "all":
        return f"all {word} (one lumped value)"
    if placement.kind in ("size", "branch"):
        return "; ".join(f"{placement.kind} {l}" for l in placement.labels)
    units = [g[0] for g in placement.groups]
    rows = tree.independent[units] if spec.unit == "joint" else np.asarray(units)
    text = tree.joint_place(rows)
    return "links after " + text if spec.unit == "link" else text
