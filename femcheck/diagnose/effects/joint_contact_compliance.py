"""``joint_contact_compliance``: the passive joints (spherical joint at B_i: Hertz point contact; universal
joint at C_i: pin line contact + simply supported pin, seed 000 §4.4.1, docs/conventions.md §5) are softer
than modelled, or missing from the model (the simplified model of seed 000 has none).

Parameter ``scale`` (-): the compliance of every S and U joint relative to the case's contact formulas,
``S_sp,i -> scale S_sp,i``, ``S_uj,i -> scale S_uj,i`` (1 = as in the detailed model, 0 = rigid joints).
It replaces the model's own value, so it also adds the joints to a simplified model.

A whole-device cause: both joint types at once, by one factor. One joint type changed alone (thinner U-joint pins,
a softer ball seat) is ``universal_joint_in_legs`` or ``spherical_joint_in_legs`` on all legs (one factor); the
evidence decides between them.
"""
import numpy as np

from femcheck.diagnose.effects import Effect, Param
from femcheck.diagnose.model import SP, UJ


class JointContactCompliance(Effect):
    id = "joint_contact_compliance"
    stage = 1
    params = (Param("scale", 0.0, 30.0, 1.0, prior_sd=2.0, doc="joint compliance / modelled contact compliance"),)

    def applicable(self, model):
        # on a level that lacks the drive and the joints (simplified) their omission is one cause,
        # ``missing_compliance``, whose special cases this scale and its partner would otherwise split
        from femcheck.diagnose.effects import get_effect
        return not get_effect("missing_compliance").applicable(model)

    def neutral(self, model):
        return np.array([float(model.base_scale[0, SP])])

    def apply(self, model, readings, values, state):
        state.scale[:, :, SP] = values[0]
        state.scale[:, :, UJ] = values[0]

    def location(self, values, lo, hi):
        return "spherical and universal joints (all legs)"

    def sample_truth(self, rng, case):
        return {"scale": float(rng.uniform(3.0, 8.0))}


EFFECT = JointContactCompliance()
