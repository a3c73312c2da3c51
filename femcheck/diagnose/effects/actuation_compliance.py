"""``actuation_compliance``: the cable-capstan-motor drive along each rail (seed 000 §4.4.2: cable
k = E A / l in series with the motor shaft torsion reflected through the capstan, k = K_rot / r^2) is
softer or stiffer than modelled, or missing from the model (the simplified model of seed 000).

Parameter ``scale`` (-): actuation compliance relative to the case's formula, ``c_act,i -> scale c_act``
(1 = modelled, 0 = rigid/locked drive). It replaces the model's value, so it also adds the drive.
"""
import numpy as np

from femcheck.diagnose.effects import Effect, Param
from femcheck.diagnose.model import ACT


class ActuationCompliance(Effect):
    id = "actuation_compliance"
    stage = 1
    params = (Param("scale", 0.0, 30.0, 1.0, prior_sd=1.0,
                    doc="actuation compliance / modelled cable + motor compliance"),)

    def applicable(self, model):
        # on a level that lacks the drive and the joints (simplified) their omission is one cause,
        # ``missing_compliance``, whose special cases this scale and its partner would otherwise split
        from femcheck.diagnose.effects import get_effect
        return not get_effect("missing_compliance").applicable(model)

    def neutral(self, model):
        return np.array([float(model.base_scale[0, ACT])])

    def apply(self, model, readings, values, state):
        state.scale[:, :, ACT] = values[0]

    def location(self, values, lo, hi):
        return "actuation (cable and motor, all legs)"

    def sample_truth(self, rng, case):
        s = rng.choice([rng.uniform(0.2, 0.4), rng.uniform(2.0, 3.5)])
        return {"scale": float(s)}


EFFECT = ActuationCompliance()
