"""The condensed joint models of one run, built once: the joint laws and the joint table condense the same joint.

``femcheck verify`` measures each passive joint's law over the device's force ladder
(:mod:`femcheck.fe_device.joint_laws`) and then checks the joint at the test point's loads
(:mod:`femcheck.fe_device.joint_check`). Both solve on a :class:`femcheck.fe_device.joint_fe.CondensedJoint`;
its mesh, assembly and Schur condensation (most of the joint's cost: 121 of 127 s for the universal joint)
depend on the load only where the mesh is graded on it (the ball's Hertz patch). :func:`condensed_joint` keeps
the last models built in this process and hands the same one to a second caller with the same inputs (the same
case object, joint, mesh level and, for the ball, largest load); :func:`release` drops them (their
factorizations hold memory).
"""
from __future__ import annotations

import gc
import logging
import math

log = logging.getLogger(__name__)

#: models kept at most (each holds its interior factorization for the recovery of the dropped points)
KEEP = 2
_models: list[tuple[tuple, object, object]] = []   # (key, case, model); the case is kept so that its id stays its own


def _key(case, joint: str, mesh: str, max_load_N, band: int) -> tuple:
    # the universal joint's mesh does not depend on the load (mesh_levels.joint_mesh_sizes); the ball's is graded on it
    load = None if joint == "universal" else (None if max_load_N is None else float(max_load_N))
    return id(case), joint, mesh, load, band


def condensed_joint(case, joint: str, mesh: str = "coarse", max_load_N: float | None = None, band: int = 0):
    """:func:`femcheck.fe_device.joint_fe.build_joint` (case's friction, default mesh options, candidate ``band``),
    reused when a model with the same inputs was built in this process (module doc)."""
    from femcheck.fe_device import joint_fe as jf

    key = _key(case, joint, mesh, max_load_N, band)
    for k, c, model in _models:
        if k == key and c is case:
            log.info("%s joint (%s mesh): condensed model reused", joint, mesh)
            return model
    model = jf.build_joint(case, joint, mesh, max_load_N=max_load_N, band=band)
    _models.append((key, case, model))
    del _models[:-KEEP]
    return model


def solve_widening(case, joint: str, mesh: str, max_load_N: float, solve):
    """``solve(model)`` on the condensed joint with the narrowest candidate band whose solution stays inside it:
    each band of :data:`femcheck.fe_device.joint_fe.CANDIDATE_BANDS` in turn (the loaded lines; both lines of each
    bore; both at twice the angle), the next one only when the contact reaches a dropped point
    (:class:`~femcheck.fe_device.joint_fe.CandidateBandError`). Past the widest band: a
    :class:`femcheck.errors.ConvergenceError` naming the joint, the bands tried and the last penetration."""
    from femcheck.errors import ConvergenceError
    from femcheck.fe_device import joint_fe as jf

    # the bands are the pin-in-bore ones; the ball keeps its Hertz band (a miss there is not a bending pin)
    bands = list(enumerate(jf.CANDIDATE_BANDS))[:None if joint == "universal" else 1]
    for band, (both, angle) in bands:
        try:
            return solve(condensed_joint(case, joint, mesh, max_load_N, band))
        except jf.CandidateBandError as exc:
            last = exc.with_traceback(None)   # its frames would keep the narrower model alive
            # the narrower model is of no further use: free its factorization before the wider one is built
            _models[:] = [m for m in _models if m[0] != _key(case, joint, mesh, max_load_N, band)]
            gc.collect()
            log.info("%s joint: contact outside candidate band %d (%s lines, %.0f deg); widening", joint, band,
                     "both" if both else "loaded", math.degrees(angle))
    both, angle = bands[-1][1]
    raise ConvergenceError(f"{joint} joint: the contact leaves every candidate band tried ({len(bands)}, "
                           f"the widest {'both lines' if both else 'the loaded lines'} within {math.degrees(angle):.0f} deg); the joint "
                           f"deforms beyond what the condensed contact model keeps ({str(last).split(';')[0]})",
                           last.residual_history, last.detail)


def release() -> None:
    """Drop the kept models (and the memory of their factorizations)."""
    _models.clear()
