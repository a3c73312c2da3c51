"""``clearance``: a dead band (joint play, backlash, carriage clearance) that the load closes progressively,
the reason for the preload of seed 000 §4.3.2 (and the backlash along the load seed 003 suspects). The
gap g_k along each axis k adds a reading

    d_k = g_k u_k (1 - exp(-|F| / F_c)),      u = F / |F|,

closed (1 - 1/e) at the closing force F_c. With a preload well above F_c eq. 1 removes it; otherwise
part of the gap is still open at the preload and inflates the deflection. The location lists the
axes whose gap is clearly non-zero.
"""
import numpy as np

from femcheck.diagnose.effects import Effect, Param

_AXES = "xyz"


class Clearance(Effect):
    id = "clearance"
    stage = 5
    params = (Param("gap_x_m", 0.0, 1e-3, 2e-5, typical=1e-5, neutral=0.0, prior_sd=5.0, doc="dead band along x, m"),
              Param("gap_y_m", 0.0, 1e-3, 2e-5, typical=1e-5, neutral=0.0, prior_sd=5.0, doc="dead band along y, m"),
              Param("gap_z_m", 0.0, 1e-3, 2e-5, typical=1e-5, neutral=0.0, prior_sd=5.0, doc="dead band along z, m"),
              Param("closing_force_N", 0.2, 50.0, 4.0, typical=1.0, prior_sd=4.0, doc="F_c, force that closes 63 % of the gap"))

    def neutral(self, model):
        return np.array([0.0, 0.0, 0.0, 4.0])

    def starts(self, model):
        return [np.array([2e-5, 2e-5, 2e-5, 4.0]), np.array([2e-5, 2e-5, 2e-5, 12.0])]

    def apply(self, model, readings, values, state):
        F = np.linalg.norm(readings.force, axis=1)
        u = np.divide(readings.force, F[:, None], out=np.zeros_like(readings.force), where=F[:, None] > 0)
        closing = 1.0 - np.exp(-F / values[3])
        state.extra += values[None, :3] * u * closing[:, None]

    def gapped_axes(self, values, lo):
        ref = np.asarray(values[:3]) if lo is None else np.asarray(lo[:3])
        return [_AXES[k] for k in range(3) if np.nan_to_num(ref[k]) > 2e-6]

    def location(self, values, lo, hi):
        axes = self.gapped_axes(values, lo)
        return ("along " + ", ".join(axes)) if axes else "no axis clearly gapped"

    def sample_truth(self, rng, case):
        n = int(rng.integers(1, 4))
        axes = sorted(rng.choice(3, size=n, replace=False))
        out = {f"gap_{_AXES[k]}_m": 0.0 for k in range(3)}
        for k in axes:   # x/y deflections are ~4x the z ones: their gaps must be larger to show through eq. 1
            out[f"gap_{_AXES[k]}_m"] = float(rng.uniform(4e-5, 1e-4) * (1.5 if k < 2 else 1.0))
        out["closing_force_N"] = float(rng.uniform(0.8, 1.6) * case.loads.detailed_preload_N)
        return out


EFFECT = Clearance()
