"""``hertz_stiffening``: extra load-dependent contact compliance in the passive joints.

A Hertz contact deflects as delta ~ F^(2/3) (seed 000 eqs. 34-36), so its secant compliance falls as
F^(-1/3): the joint stiffens with load. The effect adds to the compliance scale of every S and U joint

    scale_j(F) = scale_j,model + a (|F| / F_ref)^(-1/3),     F_ref = the case's detailed test load,

with ``a`` (-) the extra joint compliance at F_ref relative to the modelled one. Seen only through the
load-level data (preload vs total readings, the preload sweep): at the preload the extra compliance is
(P_T / P_p)^(1/3) times larger than at the test load.
"""
import numpy as np

from femcheck.diagnose.effects import Effect, Param
from femcheck.diagnose.model import SP, UJ

_F_FLOOR_N = 0.5   # the model's own floor of the Hertz linearization force (min_contact_force_N)


class HertzStiffening(Effect):
    id = "hertz_stiffening"
    stage = 2
    params = (Param("extra_compliance_at_ref", 0.0, 40.0, 1.0, neutral=0.0, prior_sd=4.0, doc="a: extra joint compliance at F_ref / modelled"),)

    def neutral(self, model):
        return np.array([0.0])

    def apply(self, model, readings, values, state):
        F_ref = float(model.case.loads.detailed_test_N)
        F = np.maximum(np.linalg.norm(state.force, axis=1), _F_FLOOR_N)
        add = values[0] * (F / F_ref) ** (-1.0 / 3.0)
        state.scale[:, :, SP] += add[:, None]
        state.scale[:, :, UJ] += add[:, None]

    def location(self, values, lo, hi):
        return "spherical and universal joint contacts (all legs)"

    def sample_truth(self, rng, case):
        return {"extra_compliance_at_ref": float(rng.uniform(3.0, 8.0))}


EFFECT = HertzStiffening()
