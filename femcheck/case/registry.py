"""Case kinds and loading: ``[meta] kind`` picks the module that validates the file.

A case kind is the module ``femcheck/case/<kind>.py``, defining ``CASE_KIND = "<kind>"`` and
``build(raw: dict, path) -> case`` (one module per kind, meshio-style registry). Only the module
of the requested kind is imported. A case object is a frozen dataclass with ``source``,
``sha256`` and ``raw_json`` fields (filled in here).
"""
from __future__ import annotations

import copy
import dataclasses
import hashlib
import json
import tomllib
from pathlib import Path

from femcheck.errors import CaseError
from femcheck.registry import plugin, plugins

_KINDS: dict[str, object] = {}
_REQUIRED = ("CASE_KIND", "build")


def case_kind_module(kind: str):
    """The module of case kind ``kind`` or None."""
    if kind not in _KINDS:
        mod = plugin("femcheck.case", kind, _REQUIRED)
        if mod is None or mod.CASE_KIND != kind:
            return None
        _KINDS[kind] = mod
    return _KINDS[kind]


def case_kinds() -> list[str]:
    """Names of the case kinds in the package (modules defining CASE_KIND and build)."""
    # a broken module is left out here and reported when its kind is requested
    return sorted(m.CASE_KIND for m in plugins("femcheck.case", _REQUIRED, skip_broken=True))


def _digest(raw: dict) -> str:
    return hashlib.sha256(json.dumps(raw, sort_keys=True, default=str).encode()).hexdigest()


def build_case(raw: dict, path):
    """Validate a parsed document into the case object of its kind."""
    meta = raw.get("meta", {})
    kind = meta.get("kind", "parallel_device") if isinstance(meta, dict) else "parallel_device"
    module = case_kind_module(kind) if isinstance(kind, str) and kind.isidentifier() else None
    if module is None:
        raise CaseError(path, "meta.kind", f"unknown case kind {kind!r}; expected one of {case_kinds()}")
    case = module.build(raw, path)
    return dataclasses.replace(case, source=str(path), sha256=_digest(raw), raw_json=json.dumps(raw, sort_keys=True))


def load_case(path):
    """Load and validate a case file (TOML) into its immutable model object.

    Raises :class:`CaseError` naming the file and the dotted key of the first problem found.
    """
    path = Path(path)
    if not path.is_file():
        raise CaseError(path, "", "case file not found")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise CaseError(path, "", "not a text file (not UTF-8); expected a TOML case file") from None
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(path, "", f"not valid TOML: {exc}") from None
    return build_case(raw, path)


def with_params(case, dotted: dict[str, object]):
    """A re-validated variant of ``case`` with values set by dotted key (``"guideway.width_radial_m"``; an entry
    of an array of tables by its index, ``"legs.0.links.1.outer_diameter_m"``).

    An unknown key raises :class:`CaseError` naming it; the original case is unchanged.
    """
    raw = copy.deepcopy(json.loads(case.raw_json))
    label = f"{case.source} (with {', '.join(f'{k}={v}' for k, v in dotted.items())})"
    expand = getattr(case, "expand_params", None)   # keys of tables a case derives (a 6-PSU layout's, from its legs)
    if expand is not None:
        dotted = expand(raw, dotted)
    for key, value in dotted.items():
        parts = key.split(".")
        node = raw
        for p in parts[:-1]:
            if isinstance(node, list) and p.isdigit():  # an array of tables: "legs.0.links.1.outer_diameter_m"
                if int(p) >= len(node):
                    raise CaseError(label, key, f"index {p} out of range; the array has {len(node)} entries")
                node = node[int(p)]
                continue
            if not isinstance(node, dict):
                raise CaseError(label, key, "no such table in the case")
            # an optional table may be absent from the file (its fields have defaults): create it and
            # let validation decide whether the key exists
            node = node.setdefault(p, {})
        if not isinstance(node, dict):
            raise CaseError(label, key, "no such key in the case")
        node[parts[-1]] = value
    new = build_case(raw, label)
    return new
