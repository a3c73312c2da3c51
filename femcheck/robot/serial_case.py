"""Serial-robot cases load through the tree: a ``serial_robot`` case (one DH chain, seed 002/003
VJM springs) becomes a one-branch ``serial_tree`` case with a single marker ``tool`` at its tool point."""
from __future__ import annotations

import json

import numpy as np


def tree_document(case) -> dict:
    """The ``serial_tree`` document of a ``serial_robot`` case (same DH rows, springs, masses; marker ``tool``)."""
    rows = []
    for i, j in enumerate(case.joints):
        row = {"name": j.name or f"j{i + 1}", "a_m": j.a_m, "alpha_deg": j.alpha_deg, "d_m": j.d_m,
               "theta_offset_deg": j.theta_offset_deg, "stiffness_Nm_per_rad": float(j.torsional_stiffness),
               "mass_kg": j.mass_kg, "com_m": list(j.com_m)}
        if case.model.vjm == "extended" and j.tilt_stiffness_Nm_per_rad is not None:
            row["tilt_stiffness_Nm_per_rad"] = list(j.tilt_stiffness_Nm_per_rad)
        rows.append(row)
    raw = json.loads(case.raw_json) if case.raw_json else {}
    meta = dict(raw.get("meta", {}))
    meta.update({"kind": "serial_tree", "name": case.meta.name})
    return {"meta": meta, "kinematics": {"convention": case.kinematics.convention},
            "gravity": {"vector_m_per_s2": list(case.gravity_m_per_s2)}, "joints": rows,
            "markers": [{"name": "tool", "link": rows[-1]["name"], "offset_m": list(case.kinematics.tool_offset_m)}]}


def as_tree_case(case):
    """``case`` itself when it is a serial tree; the converted tree case of a serial robot (errors name its file)."""
    if case.meta.kind == "serial_tree":
        return case
    from femcheck.case import serial_tree
    import dataclasses
    t = serial_tree.build(tree_document(case), case.source)
    return dataclasses.replace(t, source=case.source, sha256=case.sha256, raw_json=case.raw_json)
