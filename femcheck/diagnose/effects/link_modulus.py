"""``link_modulus``: the material stiffness of the links is mis-specified (e.g. a different alloy or temper,
or a composite tube). Guideway and proximal-link compliances (Euler-Bernoulli cantilevers, seed 000
eqs. 24-27) scale as 1/E (and 1/G at a fixed Poisson ratio), so

    S_lg,i -> S_lg,i / f,     S_prox,i -> S_prox,i / f,     f = E_true / E_case   (parameter ``E_factor``).

A whole-device cause: it moves two element types at once, the guideways *and* the proximal links (one material).
One of them changed alone in every leg is ``guideway_in_legs`` or ``proximal_link_in_legs`` on all legs (one
factor); the evidence decides between them.
"""
import numpy as np

from femcheck.diagnose.effects import Effect, Param
from femcheck.diagnose.model import LG, PROX


class LinkModulus(Effect):
    id = "link_modulus"
    stage = 3
    params = (Param("E_factor", 0.1, 10.0, 1.0, log=True, prior_sd=0.25, doc="true / assumed Young's modulus of the links"),)

    def neutral(self, model):
        return np.array([1.0])

    def apply(self, model, readings, values, state):
        state.scale[:, :, LG] /= values[0]
        state.scale[:, :, PROX] /= values[0]

    def location(self, values, lo, hi):
        return "guideways and proximal links (material modulus)"

    def sample_truth(self, rng, case):
        f = rng.choice([rng.uniform(0.45, 0.7), rng.uniform(1.6, 2.5)])
        return {"E_factor": float(f)}


EFFECT = LinkModulus()
