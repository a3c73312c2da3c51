"""``friction_hysteresis``: Coulomb friction in the guideways and joints, reflected to the TCP as a force
F_f that opposes the motion. Loading (preload, total, sweep) is resisted, ``|F_eff| = max(|F| - F_f, 0)``;
unloading from the peak P_max sticks until the force has dropped by 2 F_f,
``|F_eff| = max(min(P_max - F_f, |F| + F_f), 0)``, so the unload readings lie above the loading ones
(hysteresis) and a residual displacement remains at zero load. With F_f above the preload the preload
no longer closes the stick band, and eq. 1 underestimates the deflection.
"""
import numpy as np

from femcheck.diagnose.effects import Effect, Param


class FrictionHysteresis(Effect):
    id = "friction_hysteresis"
    stage = 0
    params = (Param("friction_N", 0.0, 60.0, 2.0, typical=5.0, neutral=0.0, prior_sd=2.0, doc="friction force reflected to the TCP, N"),)

    def neutral(self, model):
        return np.array([0.0])

    def starts(self, model):
        return [np.array([2.0]), np.array([8.0])]

    def apply(self, model, readings, values, state):
        f = values[0]
        F = np.linalg.norm(state.force, axis=1)
        unload = readings.phase == "unload"
        eff = np.maximum(np.where(unload, np.minimum(readings.peak_N - f, F + f), F - f), 0.0)
        u = np.divide(state.force, F[:, None], out=np.zeros_like(state.force), where=F[:, None] > 0)
        zero = F == 0   # unloaded to zero: the sticking displacement keeps the direction of the peak load
        ci = readings.case_index
        has_case = zero & (ci >= 0)
        u[has_case] = readings.case_unit[ci[has_case]]
        state.force = u * eff[:, None]

    def location(self, values, lo, hi):
        return "guideways and joints (friction at the TCP)"

    def sample_truth(self, rng, case):
        return {"friction_N": float(rng.uniform(1.5, 2.5) * case.loads.detailed_preload_N)}


EFFECT = FrictionHysteresis()
