"""Part parameters taken from the case, and case variants with ``[solid]`` values changed."""
from __future__ import annotations

import copy
import dataclasses
import json

from femcheck.case.registry import build_case


def with_params(case, **dotted):
    """A re-validated case variant with values set by dotted key; unlike ``case.with_params`` it also
    creates the optional ``[solid...]`` tables when the case file does not have them, e.g.
    ``with_params(case, **{"solid.spherical_joint.seat": "socket"})``."""
    raw = copy.deepcopy(json.loads(case.raw_json))
    for key, value in dotted.items():
        parts = key.split(".")
        node = raw
        for p in parts[:-1]:
            if p not in node and parts[0] == "solid":
                node[p] = {}
            node = node.get(p) if isinstance(node, dict) else None
            if not isinstance(node, dict):
                from femcheck.errors import CaseError
                raise CaseError(case.source, key, "no such table in the case")
        node[parts[-1]] = value
    label = f"{case.source} (with {', '.join(f'{k}={v}' for k, v in dotted.items())})"
    return build_case(raw, label)


def section_dict(obj) -> dict:
    """A frozen case section as a JSON-able dict (materials by name and properties)."""
    out = {}
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        if dataclasses.is_dataclass(v):
            v = section_dict(v)
        elif isinstance(v, tuple):
            v = list(v)
        out[f.name] = v
    return out
