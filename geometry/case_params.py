"""Part parameters taken from the case, and case variants with ``[solid]`` values changed."""
from __future__ import annotations

import dataclasses


def with_params(case, **dotted):
    """A re-validated case variant with values set by dotted key (:func:`femcheck.case.registry.with_params`: an
    optional table absent from the file, e.g. ``[solid.spherical_joint]``, is created; a 6-PSU layout table, e.g.
    ``spherical_joint.ball_radius_m``, writes the legs again), e.g. ``with_params(case, **{"solid.spherical_joint.seat": "socket"})``."""
    return case.with_params(**dotted)


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
