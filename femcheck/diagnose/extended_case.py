"""The corrected 6-PSU case: a diagnosis' named explanation written into a copy of the case file.

``femcheck diagnose CASE DATA.csv --extended-case OUT.toml`` turns each fitted effect of the leading explanation
into case keys, so that every command reading the case (``stiffness``, ``map``, ``sweep``, ``diagnose``) uses the
corrected device:

* element-compliance effects (``<element>_in_legs``, ``actuation_compliance``, ``joint_contact_compliance``,
  ``missing_compliance``, ``link_modulus``, ``leg_softening``) become ``[model.leg_scale]``: per leg and element
  type, the factor on the case's formula. The effects act on the (6, 5) scale in stage order exactly as in the
  fit (their own ``apply`` on a one-reading working state), then multiply what the case held;
* ``joint_rotation_release`` becomes ``[model] joint_rotation_compliance_rad_per_Nm`` (added to the case's);
* ``friction_hysteresis``, ``clearance`` and ``sensor_misalignment`` become ``[model.reading]``: they are part of
  every reading the device gives, not of its stiffness; :func:`case_reading_effects` applies them in
  :func:`femcheck.diagnose.model.predict_readings`.

``hertz_stiffening`` (a load-dependent joint compliance) has no key in the case kind and is refused by name.
Each written value carries a comment with its 95 % interval and the cause that set it.

The written case predicts, at the measured states, what the fit predicted ("after"): the keys reproduce the
fitted working state, and floats are written with ``repr`` (they read back bit for bit).
"""
from __future__ import annotations

import numpy as np

from femcheck.case.toml_edit import Edit, edited, factor_table_edits
from femcheck.chain import ELEMENTS
from femcheck.errors import FemcheckError

#: effects that only change the (legs, elements) compliance scale
SCALE_EFFECTS = ("actuation_compliance", "joint_contact_compliance", "missing_compliance", "link_modulus",
                 "leg_softening")
#: effects written as [model.reading] keys or the joint-rotation compliance
READING_EFFECTS = ("friction_hysteresis", "clearance", "sensor_misalignment")
WRITABLE = SCALE_EFFECTS + READING_EFFECTS + ("joint_rotation_release",)


def case_reading_effects(case) -> list:
    """[(Effect, values)] of the ``[model.reading]`` keys of a 6-PSU case (empty where all are neutral)."""
    r = getattr(getattr(case, "model", None), "reading", None)
    if r is None:
        return []
    from femcheck.diagnose.effects import get_effect
    out = []
    if r.friction_N > 0:
        out.append((get_effect("friction_hysteresis"), np.array([r.friction_N])))
    if any(r.clearance_gap_m):
        out.append((get_effect("clearance"), np.array([*r.clearance_gap_m, r.clearance_closing_force_N])))
    if any(r.sensor_rotation_rad):
        out.append((get_effect("sensor_misalignment"), np.array(r.sensor_rotation_rad, float)))
    return out


def _writable(effect) -> bool:
    return getattr(effect, "located", False) or effect.id in WRITABLE


def refused_causes(fit) -> list[str]:
    """Ids of the fitted effects that the 6-PSU case kind cannot hold."""
    return [e.id for e in fit.effects if not _writable(e)]


def _scale_after(effects_values, m: int = 1) -> np.ndarray:
    """(6, 5) element scales after applying scale effects (in stage order) to an all-ones working state."""
    from femcheck.diagnose.working_state import WorkingState
    st = WorkingState(force=np.zeros((m, 3)), scale=np.ones((m, 6, 5)), c_rot=0.0, extra=np.zeros((m, 3)),
                      sensor=np.eye(3))
    for eff, v in sorted(effects_values, key=lambda ev: ev[0].stage):
        eff.apply(None, None, np.asarray(v, float), st)
    return st.scale[0]


def _ci_text(lo, hi, cause: str, prob: float | None) -> str:
    p = "" if prob is None else f", p = {prob:.2f}"
    return f"95 % [{lo:.4g}, {hi:.4g}] from {cause}{p}"


def extended_case_text(case, case_text: str, diagnosis, level: str) -> str:
    """``case_text`` (the file of ``case``) with the leading explanation of ``diagnosis`` written in (module
    docstring). Refuses, by name, a cause the case kind cannot hold, and a model level other than ``detailed``
    (the case stores factors of the detailed chain's formulas)."""
    fit = diagnosis.fit
    bad = refused_causes(fit)
    if bad:
        raise FemcheckError(f"--extended-case: cause {', '.join(bad)} cannot be written into a {case.meta.kind} case "
                            f"(no key holds it); writable: <element>_in_legs, {', '.join(WRITABLE)}")
    if fit.effects and level != "detailed":
        raise FemcheckError(f"--extended-case: --model {level}; the case stores factors on the detailed chain's element "
                            "formulas, run the diagnosis with --model detailed")
    prob = {c.id: c.probability for c in diagnosis.causes}
    edits: list[Edit] = []
    scale_ev = [(e, v, lo, hi) for e, v, lo, hi in zip(fit.effects, fit.values, fit.ci_low, fit.ci_high)
                if e.id in SCALE_EFFECTS or getattr(e, "located", False)]
    if scale_ev:
        edits += _leg_scale_edits(case, scale_ev, prob)
    for e, v, lo, hi in zip(fit.effects, fit.values, fit.ci_low, fit.ci_high):
        if e.id in READING_EFFECTS or e.id == "joint_rotation_release":
            edits += _reading_edits(case, e, np.asarray(v, float), np.asarray(lo, float), np.asarray(hi, float),
                                    prob.get(e.id))
    return edited(case_text, edits, "--extended-case")


def _leg_scale_edits(case, scale_ev, prob) -> list[Edit]:
    """[model.leg_scale] rows: the fitted scale (and its interval, each parameter at its bounds with the others at
    their values) times the case's own factors; the comment names each changed leg."""
    old = case.model.leg_scale.array()
    ev = [(e, v) for e, v, _, _ in scale_ev]
    new = _scale_after(ev)
    lo_s, hi_s = new.copy(), new.copy()
    for k, (e, v, lo, hi) in enumerate(scale_ev):
        for j in range(len(v)):
            for bound in (lo, hi):
                if not np.isfinite(bound[j]):
                    continue
                vv = [np.array(x, float) for _, x in ev]
                vv[k][j] = bound[j]
                s = _scale_after([(ee, x) for (ee, _), x in zip(ev, vv)])
                lo_s, hi_s = np.minimum(lo_s, s), np.maximum(hi_s, s)
    ids = ", ".join(dict.fromkeys(e.id for e, _, _, _ in scale_ev))
    p = max((prob.get(e.id, 0.0) for e, _, _, _ in scale_ev), default=None)
    return factor_table_edits("model.leg_scale", ELEMENTS, [f"leg {i}" for i in range(6)], old, new, lo_s, hi_s,
                              ids + ("" if p is None else f", p = {p:.2f}"))


def _reading_edits(case, e, v, lo, hi, p) -> list[Edit]:
    r = case.model.reading
    if e.id == "friction_hysteresis":
        f0 = r.friction_N
        return [Edit("model.reading", "friction_N", float(f0 + v[0]), _ci_text(f0 + lo[0], f0 + hi[0], e.id, p))]
    if e.id == "clearance":
        if any(r.clearance_gap_m):
            raise FemcheckError("--extended-case: cause clearance: the case already holds a dead band "
                                "([model.reading] clearance_gap_m); two dead bands with different closing forces "
                                "have no single key, extend the original case instead")
        gaps = "; ".join(f"{a}: [{l:.3g}, {h:.3g}] m" for a, l, h in zip("xyz", lo[:3], hi[:3]))
        return [Edit("model.reading", "clearance_gap_m", [float(x) for x in v[:3]], f"95 % {gaps} from clearance"
                     + ("" if p is None else f", p = {p:.2f}")),
                Edit("model.reading", "clearance_closing_force_N", float(v[3]), _ci_text(lo[3], hi[3], e.id, p))]
    if e.id == "sensor_misalignment":
        from femcheck.kinematics.frames import matrix_to_rotvec, rotvec_to_matrix
        R = rotvec_to_matrix(v) @ rotvec_to_matrix(np.asarray(r.sensor_rotation_rad, float))
        total = matrix_to_rotvec(R)
        ci = "; ".join(f"{a}: [{l:.3g}, {h:.3g}]" for a, l, h in zip("xyz", lo, hi))
        return [Edit("model.reading", "sensor_rotation_rad", [float(x) for x in total],
                     f"fitted rotation 95 % {ci} rad, composed with the case's, from sensor_misalignment"
                     + ("" if p is None else f", p = {p:.2f}"))]
    c0 = case.model.joint_rotation_compliance_rad_per_Nm
    return [Edit("model", "joint_rotation_compliance_rad_per_Nm", float(c0 + v[0]),
                 _ci_text(c0 + lo[0], c0 + hi[0], e.id, p))]
