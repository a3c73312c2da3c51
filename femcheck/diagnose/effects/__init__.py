"""Library of model extensions: one module per physical effect, behind a small registry.

Each module defines ``EFFECT``, an :class:`Effect` with its id (the vocabulary of the issue), parameters
with bounds, an ``apply`` that changes a :class:`~femcheck.diagnose.model.WorkingState`, the location it
reports and a sampler of random hidden truths (for the virtual experiment and the tests). Adding an
effect is adding a module.
"""
from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class Param:
    """A fitted parameter: ``name`` (with unit suffix), bounds ``lower``/``upper`` (natural units), ``start``,
    ``log`` (optimized as log10), ``typical`` (optimizer scale for linear parameters), ``doc``."""

    name: str
    lower: float
    upper: float
    start: float
    log: bool = False
    typical: float = 1.0
    doc: str = ""
    #: the value meaning "no effect" (e.g. a leg factor 1, a gap 0): sitting on a bound there is no symptom
    neutral: float | None = None
    #: prior of the Laplace evidence (``femcheck.diagnose.prior``): a normal in the optimizer's scaled coordinate
    #: x = to_x(value) with standard deviation ``prior_sd`` (decades for log parameters, units of ``typical``
    #: otherwise), centred on ``prior_center`` (natural units; None = the effect's neutral value for the model),
    #: truncated to [lower, upper]. The calibration bench draws its hidden truths from the same prior.
    prior_sd: float = 1.0
    prior_center: float | None = None

    def to_x(self, v):
        return np.log10(v) if self.log else np.asarray(v) / self.typical

    def from_x(self, x):
        return 10.0 ** np.asarray(x) if self.log else np.asarray(x) * self.typical


class Effect:
    """Base class. Subclasses set ``id``, ``stage`` (application order), ``params`` and implement
    ``apply(model, readings, values, state)``."""

    id: str = ""
    stage: int = 0
    params: tuple[Param, ...] = ()
    #: value of each parameter that means "no effect" for a model with these base scales
    def neutral(self, model) -> np.ndarray:
        return np.array([p.start for p in self.params])

    #: extra -2 ln prior of an effect whose placement the diagnosis searched (see ``_located``); 0 when fixed
    penalty: float = 0.0
    #: True for the ``<element>_in_legs`` family, whose legs are screened (``femcheck.diagnose.placement``)
    located: bool = False

    def applicable(self, model) -> bool:
        return True

    def starts(self, model) -> list[np.ndarray]:
        """Start vectors (natural units) for the fit; several for non-convex effects."""
        return [np.array([p.start for p in self.params])]

    def apply(self, model, readings, values, state) -> None:  # pragma: no cover - interface
        raise NotImplementedError

    def location(self, values, ci_low, ci_high) -> str:
        return "device"

    def sample_truth(self, rng, case) -> dict[str, float]:
        """Random hidden magnitude and location (natural units) used by the tests and ``experiment simulate``."""
        return {}

    @property
    def param_names(self) -> list[str]:
        return [p.name for p in self.params]

    def values_from(self, given: dict[str, float], model) -> np.ndarray:
        """Parameter vector from a (possibly partial) dict; unnamed parameters take their neutral value."""
        unknown = sorted(set(given) - set(self.param_names))
        if unknown:
            raise KeyError(f"effect {self.id}: unknown parameter {unknown[0]!r}; expected one of {self.param_names}")
        v = self.neutral(model).astype(float)
        for i, p in enumerate(self.params):
            if p.name in given:
                v[i] = float(given[p.name])
        return v


def _discover() -> dict[str, Effect]:
    from femcheck.registry import plugins
    return {mod.EFFECT.id: mod.EFFECT for mod in plugins(__name__, ("EFFECT",)) if mod.EFFECT is not None}


_REGISTRY: dict[str, Effect] | None = None


def effects() -> dict[str, Effect]:
    """All registered effects by id (the issue's vocabulary, including ``none``)."""
    global _REGISTRY
    if _REGISTRY is None:
        _REGISTRY = _discover()
    return _REGISTRY


def get_effect(effect_id: str) -> Effect:
    reg = effects()
    if effect_id not in reg:
        raise KeyError(f"unknown effect {effect_id!r}; expected one of {', '.join(sorted(reg))}")
    return reg[effect_id]


#: The vocabulary, by what each id moves in the chain (element compliances S_e,i of element e in leg i):
#:
#: ==========================  ==============================================================================
#: id                          what it changes
#: ==========================  ==============================================================================
#: guideway_in_legs            the guideway of the legs named (any set, all six included; all six with one
#:                             factor: the guideway alone changed alike in every leg, e.g. a thinner section)
#: actuation_in_legs           the cable and motor of the legs named (alike in all six: actuation_compliance)
#: spherical_joint_in_legs     the ball joint of the legs named (all six with one factor: the seat material)
#: proximal_link_in_legs       the proximal link of the legs named (all six, one factor: the tube's alloy)
#: universal_joint_in_legs     the U joint of the legs named (all six, one factor: thinner pins)
#: actuation_compliance        the actuation of every leg, one factor
#: link_modulus                guideways *and* proximal links of every leg, one factor (their shared material)
#: joint_contact_compliance    spherical *and* universal joints of every leg, one factor
#: leg_softening               every element of a leg, one factor per leg (a loose clamp of a whole chain)
#: missing_compliance          elements the model level omits (simplified model), added back
#: hertz_stiffening            the joints' contact law (force-dependent compliance)
#: joint_rotation_release      a torsion spring in every passive joint rotation (the rigid idealization)
#: clearance                   a dead band at the TCP, closed by a force
#: friction_hysteresis         Coulomb friction at the TCP (unload readings stick)
#: sensor_misalignment         the reading frame rotated
#: ==========================  ==============================================================================
#:
#: The whole-device ids move several elements at once; a single element changed in every leg is its own
#: ``<element>_in_legs`` on all legs. Both are weighed: the evidence decides.
VOCABULARY = ("joint_contact_compliance", "actuation_compliance", "clearance", "hertz_stiffening", "leg_softening",
              "link_modulus", "friction_hysteresis", "sensor_misalignment", "joint_rotation_release",
              "guideway_in_legs", "actuation_in_legs", "spherical_joint_in_legs", "proximal_link_in_legs",
              "universal_joint_in_legs", "missing_compliance", "none")
#: the effects whose place (legs) is screened by the diagnosis (``femcheck.diagnose.placement``)
LOCATED = ("guideway_in_legs", "actuation_in_legs", "spherical_joint_in_legs", "proximal_link_in_legs",
           "universal_joint_in_legs")
