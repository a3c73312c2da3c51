"""Verification coverage of a ``parallel_device`` case: does its device FE catch a wrong law of each element kind?

The same measure as the 6-PSU's (:mod:`femcheck.coverage.element_coverage`): for every element kind e of the
device (its link names, ``drive``, ``hertz_point``, ``hertz_line``, ``measured_law``) the compliance of its law is
multiplied by ``1 + PCT/100`` in every leg (``element_scale`` of :func:`femcheck.parallel.chain_model.evaluate`).
Where the FE takes that element from the same closed form (a drive given only by its ``stiffness``, a joint without
a contact FE), the mistake would be in the FE too, so the FE's copy is scaled alike; the FE's own models do not move:

* links: beam elements of the link section (``parts = "beam"``: the cantilever law is not used, the section
  constants are shared) or meshed solids (``"solid"``: the section too is the FE's own);
* drive: its elements (:mod:`femcheck.parallel.drive_fe`) where the case describes a cable or a shaft;
* joints: their contact FE (:mod:`femcheck.parallel.joint_specimen`).

The verify check (mean analytical-FE error per direction against ``ERROR_THRESHOLDS["detailed"]``) is applied to
each mutated pair; ``fe_source`` is decided from behaviour (the FE moving with the mutation is a shared law), and
names the FE's own model otherwise: ``beam_elements``, ``meshed``, ``elements`` or ``contact_fe``.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from femcheck.coverage.element_coverage import _worst_mean_error_pct, mutation_verdict, summarize


def _fe_closed_forms_scaled(device, kind: str, factor: float):
    """``device`` with the closed-form law of ``kind`` that the beam FE reads (drive compliance, line contact,
    measured 6 x 6) ``factor`` times as compliant; links and Hertz point contacts are scaled elsewhere (the
    links' sections are not their law; the Hertz stiffness comes with the linearization)."""
    legs = []
    for leg in device.legs:
        if kind == "drive":
            leg = dataclasses.replace(leg, drive_compliance=leg.drive_compliance * factor)
        elif kind == "hertz_line":
            leg = dataclasses.replace(leg, hertz_line={k: (a * factor, b * factor, m) for k, (a, b, m) in leg.hertz_line.items()})
        elif kind == "measured_law":
            leg = dataclasses.replace(leg, measured_law={k: (S * factor, c, m) for k, (S, c, m) in leg.measured_law.items()})
        legs.append(leg)
    return dataclasses.replace(device, legs=tuple(legs))


def device_coverage(case, points=("P0", "P5"), mutation_pct: float = 50.0, *, fe_laws=None, joints: str | None = None,
                    parts: str = "beam", mesh: str = "coarse", joint_law_details: dict | None = None,
                    progress=None):
    """The :class:`~femcheck.coverage.element_coverage.CoverageResult` of a parallel device (module doc).

    ``fe_laws``: the FE's own joint and drive laws (:class:`femcheck.parallel.beam_fe.FeLaws`; None: the FE
    takes the closed forms); ``joints``: the joint idealization of both sides (default the case's);
    ``parts``, ``mesh``: the FE's links (beam | solid) and the solids' mesh level."""
    from femcheck.kinematics.directions import direction_unit
    from femcheck.kinematics.points import test_poses
    from femcheck.parallel.beam_fe import device_fe_stiffness
    from femcheck.parallel.chain_model import evaluate
    from femcheck.parallel.leg_kinematics import solve_legs
    from femcheck.verify.check import ERROR_THRESHOLDS

    if not (np.isfinite(mutation_pct) and mutation_pct > 0):
        raise ValueError(f"mutation_pct = {mutation_pct}; expected a positive percentage")
    t0 = time.perf_counter()
    note = progress or (lambda desc: None)
    joints = joints or case.model.joint_rotations
    points = tuple(points)
    dev = case.device
    P = test_poses(case, points)
    state = solve_legs(dev, P)
    units = [direction_unit(d) for d in case.loads.directions]
    wrenches = [np.concatenate([case.loads.test_N * u, np.zeros(3)]) for u in units]
    names = dev.element_names
    factor = 1.0 + mutation_pct / 100.0

    def pair(kind=None):
        """(analytical, FE) deflections along the loads (points, directions) m, ``kind`` mutated (None: none),
        and the analytical element shares (E,) averaged over points and directions."""
        scale = np.ones((dev.n_legs, len(names)))
        fe_dev = dev
        if kind is not None:
            scale[:, names.index(kind)] = factor
            fe_dev = _fe_closed_forms_scaled(dev, kind, factor)
        a, f, shares = [], [], []
        for u, W in zip(units, wrenches):
            r = evaluate(dev, P, W, model="detailed", joints=joints, element_scale=scale, state=state)
            hz = r.hertz_stiffness
            if kind == "hertz_point":
                hz = {key: v / factor for key, v in hz.items()}
            K = device_fe_stiffness(fe_dev, P, model="detailed", joints=joints, hertz_stiffness=hz, state=state,
                                    parts=parts, mesh=mesh, fe_laws=fe_laws, wrench=W)
            t = np.linalg.solve(K, np.broadcast_to(W, (len(P), 6))[..., None])[..., 0]
            a.append(r.twist[:, :3] @ u), f.append(t[:, :3] @ u), shares.append(np.nanmean(r.contributions, axis=0))
        return np.array(a).T, np.array(f).T, np.mean(shares, axis=0)

    threshold = 100 * ERROR_THRESHOLDS["detailed"]
    a0, f0, shares = pair()
    note("FE models")
    base = _worst_mean_error_pct(a0, f0)
    own = {"hertz_point": "contact_fe", "hertz_line": "contact_fe", "drive": "elements", "measured_law": "contact_fe"}
    link_kind = "meshed" if parts == "solid" else "beam_elements"
    out = []
    for j, kind in enumerate(names):
        a1, f1, _ = pair(kind)
        out.append(mutation_verdict(kind, 100 * float(shares[j]), (a0, f0), (a1, f1), base, threshold, mutation_pct,
                                    own.get(kind, link_kind)))
        note(f"mutated {kind}")
    has_joint_laws = fe_laws is not None and bool(fe_laws.joints)
    return summarize(out, mutation_pct=float(mutation_pct), points=points, mesh=mesh, fe_links=parts,
                     fe_joints="contact_fe" if has_joint_laws else "closed_form", analytical_joints=joints,
                     threshold_pct=threshold, base_error_pct=base, seconds=time.perf_counter() - t0,
                     joint_laws=dict(joint_law_details or {}))
