"""Compliance of one element type of the chain, changed in some legs only.

The family behind the ``<element>_in_legs`` effects (one module per element type): element type e (guideway,
actuation, spherical joint, proximal link, universal joint; seed 000 §4.4, ``femcheck.chain.ELEMENTS``) has, in leg
i of a leg subset L, the compliance

    S_e,i -> leg_i S_e,i     (i in L; the other legs keep the model's value),

``leg_i`` (-) relative to the case's formula for that element (Euler-Bernoulli cantilever, cable + motor, Hertz
point contact, line contact). It *replaces* the model's scale, so on a model level that lacks the element
(the simplified model has no actuation or joints) it adds the element to those legs. The registered effect
has all six legs (``leg0..leg5``, used to hide a truth in a virtual experiment); a diagnosis fits
:meth:`ElementInLegs.restricted` placements chosen by :func:`femcheck.diagnose.placement.screen_placements`.

Any leg set is a placement, all six legs included. The element changed alike in every leg (a softer alloy of the
proximal-link tubes, thinner U-joint pins, a softer cable) has its own placement :meth:`ElementInLegs.uniform`:
all six legs, one parameter ``all_legs``,

    S_e,i -> all_legs S_e,i     (i = 0..5),

so that it is weighed with one parameter like the whole-device ids and not with six. It differs from them in what
it moves: ``link_modulus`` scales the guideways and the proximal links together, ``joint_contact_compliance`` both
joints, ``leg_softening`` every element of a leg, ``actuation_compliance`` is the actuation's own all-legs scale
(the same law as ``actuation_in_legs`` uniform on all six legs, so the actuation has no uniform placement of its
own); the evidence decides between them.
"""
from __future__ import annotations

import math

import numpy as np

from femcheck.chain import ELEMENTS
from femcheck.diagnose.effects import Effect, Param

#: human names of the element types (location strings)
LABEL = {"lg": "guideway", "act": "actuation (cable and motor)", "sp": "spherical joint", "prox": "proximal link",
         "uj": "universal joint"}


class ElementInLegs(Effect):
    """Compliance scale of element ``element`` (key of ``femcheck.chain.ELEMENTS``) in the legs ``legs``."""

    stage = 1
    located = True

    def __init__(self, element: str, effect_id: str, legs=tuple(range(6)), uniform: bool = False,
                 uniform_cause: str | None = None):
        self.element = element
        #: the vocabulary id whose law *is* this element's uniform all-legs change (``actuation_compliance`` for the
        #: actuation): the screen then leaves the uniform placement to it, one explanation holding the mass, not two
        self.uniform_cause = uniform_cause
        self.column = ELEMENTS.index(element)
        self.id = effect_id
        self.uniform = bool(uniform)
        self.legs = tuple(range(6)) if self.uniform else tuple(sorted(int(i) for i in legs))
        if self.uniform:
            self.params = (Param("all_legs", 0.0, 30.0, 1.0,
                                 doc=f"{LABEL[element]} compliance in every leg / the case's formula"),)
        else:
            self.params = tuple(Param(f"leg{i}", 0.0, 30.0, 1.0,
                                      doc=f"{LABEL[element]} compliance in leg {i} / the case's formula")
                                for i in self.legs)

    def __repr__(self) -> str:
        return f"ElementInLegs({self.element!r}, legs={'all, one factor' if self.uniform else self.legs})"

    def __eq__(self, other) -> bool:
        return isinstance(other, ElementInLegs) and (other.id, other.legs, other.uniform) == (self.id, self.legs,
                                                                                               self.uniform)

    def __hash__(self) -> int:
        return hash((self.id, self.legs, self.uniform))

    @property
    def penalty(self) -> float:
        """Extended-BIC term 2 ln C(6, k) of a placement of k legs picked among 6 (Chen & Chen, Biometrika 95 (2008)
        759), added to -2 ln evidence: the placement was chosen by a search, not fixed before the data (0 for all
        six legs: one such subset)."""
        return 2.0 * math.log(math.comb(6, len(self.legs)))

    def restricted(self, legs) -> "ElementInLegs":
        return ElementInLegs(self.element, self.id, legs, uniform_cause=self.uniform_cause)

    def uniform_all(self) -> "ElementInLegs":
        """The element changed alike in all six legs: one factor (module docstring)."""
        return ElementInLegs(self.element, self.id, uniform=True, uniform_cause=self.uniform_cause)

    def neutral(self, model) -> np.ndarray:
        base = np.array(model.base_scale)[list(self.legs), self.column].astype(float)
        return np.array([base.mean()]) if self.uniform else base

    def starts(self, model) -> list[np.ndarray]:
        return [np.ones(len(self.params))]

    def apply(self, model, readings, values, state) -> None:
        state.scale[:, list(self.legs), self.column] = values[None, :]   # one value broadcasts over the six legs

    def location(self, values, lo, hi) -> str:
        if self.uniform:
            return f"{LABEL[self.element]} in all legs (one factor)"
        legs = ", ".join(map(str, self.legs))
        return f"{LABEL[self.element]} in leg{'s' if len(self.legs) > 1 else ''} {legs}"

    def sample_truth(self, rng, case) -> dict[str, float]:
        n = int(rng.integers(1, 3))
        legs = sorted(int(i) for i in rng.choice(6, size=n, replace=False))
        return {f"leg{i}": float(rng.uniform(1.8, 3.0)) for i in legs}

    def truth_legs(self, params: dict, model) -> list[int]:
        """Legs whose hidden value differs from the model's (for benches and tests)."""
        base = np.array(model.base_scale)[:, self.column]
        if "all_legs" in params:
            return [i for i in range(6) if not np.isclose(params["all_legs"], base[i])]
        return [i for i in range(6) if f"leg{i}" in params and not np.isclose(params[f"leg{i}"], base[i])]
