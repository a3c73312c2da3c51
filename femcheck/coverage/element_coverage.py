"""Verification coverage by mutation: does the FE catch a wrong law of each element of the chain?

For every element e of the detailed chain (guideway, actuation, spherical joint, proximal link,
universal joint) the compliance of its *law* is multiplied by ``1 + PCT/100`` where the law is defined
(``[model.law_scale]``, applied in :func:`femcheck.chain.device_parameters`). The analytical model sees
the change. The FE never reads the law; where it models the element by a closed form of its own, the same law
restated from the materials (:func:`femcheck.fe_device.contact_scales.closed_form_elements`), a mistake in the
law would be in that restatement too, so the mutation is applied to it as well
(:meth:`~femcheck.fe_device.contact_scales.DeviceSprings.with_law_scale`); a meshed part, a contact-FE joint law
or the actuation elements do not move. The verify check (mean analytical-FE error per direction against
``ERROR_THRESHOLDS["detailed"]``) is then applied to the mutated pair.

Per element:

- ``share_pct``: the element's mean share of the complementary energy (docs/conventions.md §7) at the points;
- ``fe_source``: from behaviour, not a label: ``shared_closed_form`` when the FE deflection moves with the
  mutation like the analytical one (ratio of the relative changes >= 0.5: the FE reuses the law), else
  ``meshed`` (the FE does not move: its element is an independent model), or ``contact_fe`` when the FE does
  not move and that element's FE response is the law measured by the joint's contact FE
  (:mod:`femcheck.fe_device.joint_laws`; behaviour decides independent vs shared, the FE's record of what
  supplied the element names the kind of independent model);
- ``error_change_pct``: change of the worst mean error (percentage points) caused by the mutation;
- ``detected``: whether the verify check fails on the mutated pair and passes on the unmutated one;
- ``min_detectable_pct``: the smallest mutation the check catches, by linearization of the worst mean error
  in the mutation (the analytical deflection is linear in each law's compliance up to the Hertz
  linearization); ``None`` when no mutation is caught: the error does not move, or the law is shared
  (both sides move alike; the small error change left is the load protocol's, not a check of the law).

Two shares summarize the elements:

- ``covered_share_pct``: the summed share of the elements whose mutation, at the stated size, the check
  catches (``detected``) on a law the FE does not share: what the verification actually guards at that size;
- ``independent_share_pct``: the summed share of the elements the FE models on its own (``fe_source`` not
  ``shared_closed_form``), caught or not: the most a larger mutation could cover.

When the unmutated model already fails the check (``base_passes`` false: the analytical model and the FE
disagree beyond the threshold, e.g. the closed-loop actuation FE against eq. 44, docs/verify.md), a mutation
cannot be told from that disagreement: no element counts as ``detected`` and ``covered_share_pct`` is 0;
``min_detectable_pct`` is then 0 for the independently modelled elements and the figures should be read
together with ``base_error_pct``.

Cost: one FE build (meshes and condensed super-elements) at the points; each mutation re-solves only the
dense leg/platform algebra of :func:`femcheck.fe_device.device_model.solve_point` with the mutated case,
reusing the super-elements (they depend on mesh and materials, which no law mutation touches).
"""
from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np

from femcheck.chain import ELEMENT_NAMES, ELEMENTS

log = logging.getLogger(__name__)

#: the FE's relative change / the analytical relative change above which the FE counts as reusing the law
SHARED_RATIO = 0.5
#: the chain elements whose FE response can be a joint's contact-FE law
JOINT_OF_ELEMENT = {"spherical_joint": "spherical", "universal_joint": "universal"}
#: min_detectable_pct above this is reported as not detectable (a law off by 100x is not a plausible error)
MAX_DETECTABLE_PCT = 10_000.0


@dataclasses.dataclass(frozen=True)
class ElementCoverage:
    element: str
    share_pct: float
    fe_source: str
    error_change_pct: float
    detected: bool
    min_detectable_pct: float | None
    fe_response_ratio: float

    def as_json(self) -> dict:
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class CoverageResult:
    mutation_pct: float
    covered_share_pct: float
    independent_share_pct: float
    points: tuple
    mesh: str
    fe_joints: str
    analytical_joints: str
    threshold_pct: float
    base_error_pct: float
    elements: tuple
    seconds: float
    joint_laws: dict = dataclasses.field(default_factory=dict)
    #: parallel devices: the FE's links, "beam" (beam elements) or "solid" (meshed at ``mesh``); None: the 6-PSU FE
    fe_links: str | None = None

    @property
    def base_passes(self) -> bool:
        """Whether the unmutated analytical-FE pair passes the check (else every mutation is caught trivially)."""
        return self.base_error_pct <= self.threshold_pct

    def as_json(self) -> dict:
        out = {k: v for k, v in dataclasses.asdict(self).items()
               if k != "elements" and not (k == "fe_links" and v is None)}   # the 6-PSU's keys as they were
        out["base_passes"] = self.base_passes
        out["points"] = list(self.points)
        out["elements"] = [e.as_json() for e in self.elements]
        return out

    def rows(self) -> list[dict]:
        """Table rows (percent columns) for reports."""
        return [{"element": e.element, "share_pct": round(e.share_pct, 2), "fe_source": e.fe_source,
                 "error_change_pct": round(e.error_change_pct, 3), "detected": e.detected,
                 "min_detectable_pct": None if e.min_detectable_pct is None else round(e.min_detectable_pct, 1)}
                for e in self.elements]


#: expected wall time (s, the shared 2-core machine) behind the progress ETA of ``femcheck coverage``: a joint
#: law's contact FE at the coarse joint mesh when not cached (27 s ball, 52 s universal joint, measured), the
#: device FE models per point and one mutation (dense re-solves) per point (these two are estimates, not measured)
LAW_S = {"spherical": 27.0, "universal": 52.0}
FE_MODELS_S_PER_POINT = {"coarse": 8.0, "default": 25.0, "fine": 90.0}
MUTATION_S_PER_POINT = 1.0


def progress_weights(n_points: int, mesh: str, laws_cached: dict | None) -> list[float]:
    """Expected costs of the steps that ``coverage`` reports: the joint laws (``laws_cached`` {joint: bool};
    None: no laws measured), the FE models, one step per mutated element."""
    laws = [] if laws_cached is None else [0.01 if laws_cached[j] else LAW_S[j] for j in laws_cached]
    return laws + [FE_MODELS_S_PER_POINT.get(mesh, 25.0) * n_points] + [MUTATION_S_PER_POINT * n_points] * len(ELEMENTS)


def _deflections(case, points, directions, fe_models, fe_joints, analytical_joints, joint_laws=None, springs=None):
    """(analytical, FE) deflections along the load, each (n_points, n_directions) m; ``springs``: the FE's
    closed-form springs (default: the case's)."""
    from femcheck.fe_device.device_model import solve_point
    from femcheck.verify.analytical import run_analytical

    av = run_analytical(case, points, directions)
    a = np.array([[av.deflection(p, d, "detailed", analytical_joints) for d in directions] for p in points])
    f = np.array([[solve_point(case, fe_models[p], ("detailed",), (fe_joints,), (d,), joint_laws=joint_laws,
                               springs=springs)
                   .cases[("detailed", fe_joints, d)]
                   .deflection_m for d in directions] for p in points])
    return a, f, av


def _worst_mean_error_pct(a, f) -> float:
    """The largest over directions of the mean over points of |a - f| / |f| (the verify check's statistic), %."""
    return float(100 * np.max(np.mean(np.abs(a - f) / np.abs(f), axis=0)))


def mutation_verdict(name: str, share_pct: float, unmutated, mutated, base: float, threshold: float,
                     mutation_pct: float, independent_kind: str) -> ElementCoverage:
    """One element's row (module doc) from the (analytical, FE) deflections without and with its mutation:
    ``fe_source`` shared when the FE moved with the analytical model (ratio >= SHARED_RATIO), else
    ``independent_kind`` (what models the element in the FE: 'meshed', 'contact_fe', 'elements')."""
    (a0, f0), (a1, f1) = unmutated, mutated
    da = float(np.mean(np.abs(a1 / a0 - 1)))
    df = float(np.mean(np.abs(f1 / f0 - 1)))
    ratio = df / da if da > 0 else float("nan")
    source = "shared_closed_form" if ratio >= SHARED_RATIO else independent_kind
    err = _worst_mean_error_pct(a1, f1)
    slope = (err - base) / mutation_pct                    # percentage points of error per % of mutation
    detected = err > threshold >= base        # a base that already fails cannot tell a mutation apart
    # a shared law moves both sides alike: what little the error moves comes from the load protocol
    # (secant vs tangent Hertz), not from a check of the law, so no mutation of it counts as caught
    if source != "shared_closed_form" and slope > 1e-9:
        mdp = max((threshold - base) / slope, 0.0)           # 0: the unmutated pair already fails
        mdp = float(mdp) if mdp <= MAX_DETECTABLE_PCT else None
    else:
        mdp = None
    return ElementCoverage(element=name, share_pct=share_pct, fe_source=source, error_change_pct=err - base,
                           detected=bool(detected), min_detectable_pct=mdp, fe_response_ratio=ratio)


def summarize(elements, **fields) -> CoverageResult:
    """The :class:`CoverageResult` of the element rows: covered share (detected, not shared) and independent share."""
    independent = [e for e in elements if e.fe_source != "shared_closed_form"]
    return CoverageResult(covered_share_pct=float(sum(e.share_pct for e in independent if e.detected)),
                          independent_share_pct=float(sum(e.share_pct for e in independent)),
                          elements=tuple(elements), **fields)


def element_coverage(case, points=("P0", "P5"), mutation_pct: float = 50.0, mesh: str = "coarse",
                     fe_joints: str = "contact", analytical_joints: str = "released", jobs: int = 1,
                     fe_models=None, progress=None, joint_laws=None) -> CoverageResult:
    """Measure the coverage (module docstring). ``fe_models``: {point: PointModel} to reuse (else built);
    ``joint_laws``: the contact-FE joint laws the FE uses (:class:`femcheck.fe_device.joint_laws.JointLaws`;
    None: the closed forms)."""
    from femcheck.fe_device.contact_scales import closed_form_elements, device_springs
    from femcheck.fe_device.joint_laws import CLOSED_FORM
    from femcheck.verify.check import ERROR_THRESHOLDS
    from femcheck.verify.fe import run_fe

    if not (np.isfinite(mutation_pct) and mutation_pct > 0):
        raise ValueError(f"mutation_pct = {mutation_pct}; expected a positive percentage")
    t0 = time.perf_counter()
    note = progress or (lambda desc: None)
    points = tuple(points)
    directions = tuple(case.loads.directions)
    if fe_models is None:
        fe = run_fe(case, points, levels=("detailed",), mesh=mesh, jobs=jobs)
        fe_models = fe.models
    note("FE models")
    threshold = 100 * ERROR_THRESHOLDS["detailed"]
    sources = (joint_laws or CLOSED_FORM).sources()
    restated = closed_form_elements(case, joint_laws)   # the FE's own closed forms of the same laws
    a0, f0, av = _deflections(case, points, directions, fe_models, fe_joints, analytical_joints, joint_laws)
    base = _worst_mean_error_pct(a0, f0)
    if base > threshold:
        log.warning("coverage: the unmutated model already fails the check (worst mean error %.2f %% > %.0f %%)",
                    base, threshold)
    shares = av.mean_contributions(analytical_joints)
    factor = 1.0 + mutation_pct / 100.0
    out = []
    for e in ELEMENTS:
        variant = case.with_params(**{f"model.law_scale.{e}": factor})
        springs = device_springs(case).with_law_scale(e, factor) if e in restated else None
        a1, f1, _ = _deflections(variant, points, directions, fe_models, fe_joints, analytical_joints, joint_laws,
                                 springs)
        joint = JOINT_OF_ELEMENT.get(ELEMENT_NAMES[e])
        kind = "contact_fe" if joint is not None and sources[joint] == "contact_fe" else "meshed"
        out.append(mutation_verdict(ELEMENT_NAMES[e], 100 * shares[ELEMENT_NAMES[e]], (a0, f0), (a1, f1), base,
                                    threshold, mutation_pct, kind))
        note(f"mutated {ELEMENT_NAMES[e]}")
        log.info("coverage %s: share %.1f %%, FE/analytical change %.3f, error %.2f -> %.2f %%", e,
                 out[-1].share_pct, out[-1].fe_response_ratio, base, base + out[-1].error_change_pct)
    return summarize(out, mutation_pct=float(mutation_pct), points=points, mesh=mesh, joint_laws=sources,
                     fe_joints=fe_joints, analytical_joints=analytical_joints, threshold_pct=threshold,
                     base_error_pct=base, seconds=time.perf_counter() - t0)
