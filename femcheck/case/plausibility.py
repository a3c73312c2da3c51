"""Case dimensions out of proportion with the device they belong to (a unit slip, e.g. 6 for 0.006).

The schema checks signs and orderings; it cannot know that a 6 m tube diameter on a device 0.3 m across is a
millimetre value in a metre key. :func:`dimension_warnings` judges every cross-section or joint size (a key named
``*diameter*_m``, ``*radius*_m``, ``*width*_m``, ``*depth*_m``, ``*thickness*_m``) against the device's overall
size: larger than the device itself, or below 1/``SMALL`` of it (10 um on a 0.1 m device), it is implausible.
The device size is the largest of its geometry's radii and lengths (6-PSU) or of the distances between its joint
centres (a general parallel device).
"""
from __future__ import annotations

import dataclasses
import itertools

import numpy as np

#: a section or joint size below device size / SMALL is implausible (clearances and gaps are not judged)
SMALL = 1e4
_SIZE_WORDS = ("diameter", "radius", "width", "depth", "thickness")
_GEOMETRY_KEYS = ("base_radius_m", "platform_radius_m", "proximal_link_length_m", "rail_length_m")


def _walk(obj, path: str):
    """(dotted key, value) of every field of the frozen dataclasses below ``obj`` (tuples entered with [i])."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        for f in dataclasses.fields(obj):
            yield from _walk(getattr(obj, f.name), f"{path}.{f.name}" if path else f.name)
    elif isinstance(obj, (tuple, list)) and obj and all(dataclasses.is_dataclass(o) for o in obj):
        for i, o in enumerate(obj):
            yield from _walk(o, f"{path}[{i}]")
    else:
        yield path, obj


def device_size_m(case) -> float:
    """Overall size (m) of the device: geometry radii and lengths, else the largest distance between joint centres."""
    fields = list(_walk(case, ""))
    geo = [float(v) for k, v in fields if k.rsplit(".", 1)[-1] in _GEOMETRY_KEYS and isinstance(v, (int, float))]
    pts = [np.asarray(v, float) for k, v in fields if k.endswith("point_m") and v is not None and np.size(v) == 3]
    spread = max((float(np.linalg.norm(a - b)) for a, b in itertools.combinations(pts, 2)), default=0.0)
    return max(geo + [spread])


def dimension_warnings(case) -> list[str]:
    """One line per implausible section or joint size of ``case`` (module docstring); [] when all are plausible or
    the device size is unknown."""
    size = device_size_m(case)
    if not size > 0:
        return []
    out = []
    for key, v in _walk(case, ""):
        name = key.rsplit(".", 1)[-1]
        if not (name.endswith("_m") and any(w in name for w in _SIZE_WORDS)) or not isinstance(v, (int, float)) \
                or isinstance(v, bool) or v == 0:
            continue
        if v > size:
            out.append(f"{case.source}: {key} = {v:g} m is larger than the device itself ({size:.3g} m across): "
                       f"mm written as m?")
        elif v < size / SMALL:
            out.append(f"{case.source}: {key} = {v:g} m is below 1/{SMALL:g} of the device ({size:.3g} m across): "
                       f"a unit slip?")
    return out
