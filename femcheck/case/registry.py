"""Case kinds and loading: ``[meta] kind`` picks the module that validates the file.

A case-kind module lives in ``femcheck/case/`` and defines ``CASE_KIND`` (a string) and
``build(raw: dict, path) -> case``; it is found automatically (one module per kind, meshio-style
registry). A case object is a frozen dataclass with ``source``, ``sha256`` and ``raw_json`` fields.
"""
from __future__ import annotations

import copy
import dataclasses
import hashlib
import importlib
import json
import pkgutil
import tomllib
from pathlib import Path

from femcheck.errors import CaseError

_KINDS: dict[str, object] = {}


def case_kinds() -> dict[str, object]:
    """{kind: module} of every case kind found in the package."""
    if not _KINDS:
        import femcheck.case as pkg
        for info in pkgutil.iter_modules(pkg.__path__):
            mod = importlib.import_module(f"femcheck.case.{info.name}")
            kind = getattr(mod, "CASE_KIND", None)
            if kind and hasattr(mod, "build"):
                _KINDS[kind] = mod
    return _KINDS


def _digest(raw: dict) -> str:
    return hashlib.sha256(json.dumps(raw, sort_keys=True, default=str).encode()).hexdigest()


def build_case(raw: dict, path):
    """Validate a parsed document into the case object of its kind."""
    meta = raw.get("meta", {})
    kind = meta.get("kind", "haptic_6psu") if isinstance(meta, dict) else "haptic_6psu"
    kinds = case_kinds()
    if kind not in kinds:
        raise CaseError(path, "meta.kind", f"unknown case kind {kind!r}; expected one of {sorted(kinds)}")
    case = kinds[kind].build(raw, path)
    return dataclasses.replace(case, source=str(path), sha256=_digest(raw), raw_json=json.dumps(raw, sort_keys=True))


def load_case(path):
    """Load and validate a case file (TOML) into its immutable model object.

    Raises :class:`CaseError` naming the file and the dotted key of the first problem found.
    """
    path = Path(path)
    if not path.is_file():
        raise CaseError(path, "", "case file not found")
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(path, "", f"not valid TOML: {exc}") from None
    return build_case(raw, path)


def with_params(case, dotted: dict[str, object]):
    """A re-validated variant of ``case`` with values set by dotted key (``"guideway.width_radial_m"``).

    An unknown key raises :class:`CaseError` naming it; the original case is unchanged.
    """
    raw = copy.deepcopy(json.loads(case.raw_json))
    label = f"{case.source} (with {', '.join(f'{k}={v}' for k, v in dotted.items())})"
    for key, value in dotted.items():
        parts = key.split(".")
        node = raw
        for p in parts[:-1]:
            if not isinstance(node, dict) or p not in node:
                raise CaseError(label, key, "no such table in the case")
            node = node[p]
        if not isinstance(node, dict):
            raise CaseError(label, key, "no such key in the case")
        if parts[-1] not in node:
            # a key may be absent because it has a default; let validation decide whether it exists
            pass
        node[parts[-1]] = value
    new = build_case(raw, label)
    return new
