"""``joint_rotation_release``: the passive S and U joints carry less moment than the ``rigid`` idealization of
the paper assumes (docs/conventions.md §5 "Joint idealization"). Each passive joint rotation gets a torsional
spring of compliance c (rad/(N m)), an extra chain compliance ``c Jp Jp^T`` (seed 001's passive-joint
elimination with springs instead of free joints): c = 0 is the paper's rigid model, c -> infinity the
``released`` model (two-force legs). Applies to a ``rigid`` base model only.
"""
import numpy as np

from femcheck.diagnose.effects import Effect, Param


class JointRotationRelease(Effect):
    id = "joint_rotation_release"
    stage = 4
    params = (Param("compliance_rad_per_Nm", 1e-5, 1e3, 1e-2, log=True, prior_sd=1.0,
                    prior_center=0.1, doc="passive joint rotation compliance c"),)

    def neutral(self, model):
        return np.array([0.0])

    def applicable(self, model):
        return model.joints == "rigid"

    def starts(self, model):
        return [np.array([1e-2]), np.array([1.0])]

    def apply(self, model, readings, values, state):
        state.c_rot = float(values[0])

    def location(self, values, lo, hi):
        c = float(values[0])
        return "passive S/U joint rotations (" + ("nearly released" if c > 1.0 else "partially released") + ")"

    def sample_truth(self, rng, case):
        return {"compliance_rad_per_Nm": float(10 ** rng.uniform(np.log10(0.02), np.log10(2.0)))}


EFFECT = JointRotationRelease()
