"""``leg_softening``: one or more legs (chains) are softer than the others, e.g. a loose clamp, a damaged
tube or a slack cable in that leg. Every element compliance of chain i is multiplied by ``leg{i}``:

    S_e,i -> leg_i S_e,i     (e = guideway, actuation, joints, proximal link; leg_i >= 1).

The location is the list of legs whose factor is clearly above 1 (lower 95 % bound > 1.05).

A whole-leg cause: every element of a leg by the same factor (a loose clamp of the whole chain). One element type
changed in some legs is ``<element>_in_legs``; two element types changed (a thinner guideway and a softer cable) are
a pair of element causes, with their own factors; the evidence decides between them.
"""
import numpy as np

from femcheck.diagnose.effects import Effect, Param

_SOFT_MARGIN = 1.05   # a leg counts as softened if its factor's lower 95 % bound exceeds this


class LegSoftening(Effect):
    id = "leg_softening"
    stage = 3
    params = tuple(Param(f"leg{i}", 1.0, 20.0, 1.1, neutral=1.0, prior_sd=2.0, doc=f"compliance factor of chain {i}") for i in range(6))

    def neutral(self, model):
        return np.ones(6)

    def apply(self, model, readings, values, state):
        state.scale *= values[None, :, None]

    def soft_legs(self, values, lo) -> list[int]:
        lo = np.asarray(values) if lo is None else np.asarray(lo)
        return [int(i) for i in np.flatnonzero(np.nan_to_num(lo, nan=1.0) > _SOFT_MARGIN)]

    def location(self, values, lo, hi):
        legs = self.soft_legs(values, lo)
        return "legs " + ", ".join(map(str, legs)) if legs else "no leg clearly softer"

    def sample_truth(self, rng, case):
        n = int(rng.integers(1, 3))
        legs = rng.choice(6, size=n, replace=False)
        return {f"leg{int(i)}": float(rng.uniform(2.5, 5.0)) for i in sorted(legs)}


EFFECT = LegSoftening()
