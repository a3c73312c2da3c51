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

import logging

log = logging.getLogger(__name__)

#: models kept at most (each holds its interior factorization for the recovery of the dropped points)
KEEP = 2
_models: list[tuple[tuple, object, object]] = []   # (key, case, model); the case is kept so that its id stays its own


def _key(case, joint: str, mesh: str, max_load_N) -> tuple:
    # the universal joint's mesh does not depend on the load (mesh_levels.joint_mesh_sizes); the ball's is graded on it
    load = None if joint == "universal" else (None if max_load_N is None else float(max_load_N))
    return id(case), joint, mesh, load


def condensed_joint(case, joint: str, mesh: str = "coarse", max_load_N: float | None = None):
    """:func:`femcheck.fe_device.joint_fe.build_joint` (case's friction, default mesh options), reused when a model
    with the same inputs was built in this process (module doc)."""
    from femcheck.fe_device import joint_fe as jf

    key = _key(case, joint, mesh, max_load_N)
    for k, c, model in _models:
        if k == key and c is case:
            log.info("%s joint (%s mesh): condensed model reused", joint, mesh)
            return model
    model = jf.build_joint(case, joint, mesh, max_load_N=max_load_N)
    _models.append((key, case, model))
    del _models[:-KEEP]
    return model


def release() -> None:
    """Drop the kept models (and the memory of their factorizations)."""
    _models.clear()
