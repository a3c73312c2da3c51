"""``missing_compliance``: the model omits the compliance of the drive and of the passive joints. The simplified model of seed 000 (guideways and proximal links only) against a
device whose actuation and joints are compliant: the paper's storyline (Table 2 -> Table 3).

It adds, in every leg, the three elements the model level lacks, each with its own non-negative scale of the
case's closed form (seed 000 §4.4, docs/conventions.md §5):

    c_act,i = a * (cable E A / l in series with the motor K_rot / r^2)^-1          (``actuation_scale`` a >= 0)
    S_sp,i  = s * Hertz point contact of the ball in its seat, linearized at the reading's load
                                                                                  (``spherical_joint_scale`` s >= 0)
    S_uj,i  = u * line contact of the pin in its bore + simply supported pin      (``universal_joint_scale`` u >= 0)

0 = the element stays absent (the model as given; no symptom on that bound), 1 = the case's formula (the detailed
model). Applicable only to a model that lacks all three (the ``simplified`` level); on the detailed model the
elements exist and ``actuation_compliance`` / ``joint_contact_compliance`` / the located ``*_in_legs`` scale them.
Where it applies, those two all-legs scales do not: the pair of them is its special case (one scale for both
joints), and as two causes they took the evidence from the one omission (measured: 0.79 against 0.19).
"""
import numpy as np

from femcheck.diagnose.effects import Effect, Param
from femcheck.diagnose.model import ACT, SP, UJ

_COLUMNS = (ACT, SP, UJ)


class MissingCompliance(Effect):
    id = "missing_compliance"
    stage = 1
    params = (Param("actuation_scale", 0.0, 30.0, 1.0, neutral=0.0, prior_sd=1.0, doc="added drive compliance / the case's formula"),
              Param("spherical_joint_scale", 0.0, 30.0, 1.0, neutral=0.0, prior_sd=1.0,
                    doc="added spherical-joint (Hertz point contact) compliance / the case's formula"),
              Param("universal_joint_scale", 0.0, 30.0, 1.0, neutral=0.0, prior_sd=1.0,
                    doc="added universal-joint (line contact) compliance / the case's formula"))

    def applicable(self, model) -> bool:
        return bool(np.all(np.asarray(model.base_scale)[:, list(_COLUMNS)] == 0.0))

    def neutral(self, model):
        return np.zeros(3)

    def apply(self, model, readings, values, state):
        for col, v in zip(_COLUMNS, values):
            state.scale[:, :, col] = v

    def location(self, values, lo, hi):
        names = ("actuation", "spherical joints", "universal joints")
        ref = np.asarray(values) if lo is None else np.nan_to_num(np.asarray(lo))
        added = [n for n, v in zip(names, ref) if v > 0.0]
        return ("adds what the model omits: " + ", ".join(added) + " (all legs)") if added else \
            "no omitted element clearly needed"

    def sample_truth(self, rng, case):
        return {"actuation_scale": float(rng.uniform(0.7, 1.5)), "spherical_joint_scale": float(rng.uniform(0.7, 1.5)),
                "universal_joint_scale": float(rng.uniform(0.7, 1.5))}


EFFECT = MissingCompliance()
