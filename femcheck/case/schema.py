"""Declarative validation of TOML tables into frozen dataclasses.

A case section is a frozen dataclass whose fields carry their unit and check in the field
metadata (``quantity(...)``). ``build_section`` walks the fields, validates type, units and
range, resolves material names and rejects unknown keys, raising :class:`CaseError` with the
file name and the dotted key. One general mechanism: every case kind (6-PSU device, serial
robot, ...) declares its sections this way and gets the same error messages.
"""
from __future__ import annotations

import dataclasses
import math
import typing
from dataclasses import MISSING, field
from typing import Any, Callable, Literal, get_args, get_origin

from femcheck.errors import CaseError

#: named range checks: name -> (predicate, text used in "expected ...")
CHECKS: dict[str, tuple[Callable[[float], bool], str]] = {
    "positive": (lambda v: v > 0, "> 0"),
    "nonnegative": (lambda v: v >= 0, ">= 0"),
    "poisson": (lambda v: -1.0 < v < 0.5, "a Poisson ratio in (-1, 0.5)"),
    "fraction": (lambda v: 0.0 <= v <= 1.0, "in [0, 1]"),
    "any": (lambda v: True, "a number"),
}


def quantity(unit: str = "", *, check: str = "positive", default: Any = MISSING, doc: str = ""):
    """A validated case field: ``unit`` (SI, shown in errors and docs), named ``check``, optional default."""
    if check not in CHECKS:
        raise ValueError(f"unknown check {check!r}")
    return field(default=default, metadata={"unit": unit, "check": check, "doc": doc})


def option(default: Any = MISSING, *, doc: str = ""):
    """A validated non-numeric case field (string choice, bool, material name, nested table)."""
    if isinstance(default, (list, dict)):
        raise ValueError("mutable defaults are not allowed in case sections")
    return field(default=default, metadata={"doc": doc})


@dataclasses.dataclass(frozen=True)
class Material:
    """Isotropic linear-elastic material.

    Attributes: ``name``; ``E_Pa`` Young's modulus (Pa); ``nu`` Poisson ratio (-);
    ``density_kg_m3`` (kg/m^3, used by modal analysis and mass estimates).
    """

    name: str
    E_Pa: float = quantity("Pa")
    nu: float = quantity("-", check="poisson")
    density_kg_m3: float = quantity("kg/m^3", default=7850.0)

    @property
    def G_Pa(self) -> float:
        """Shear modulus G = E / (2 (1 + nu)), Pa."""
        return self.E_Pa / (2.0 * (1.0 + self.nu))


class Context:
    """What a section needs while it is built: the file name and the materials table."""

    def __init__(self, path, materials: dict[str, Material] | None = None):
        self.path = path
        self.materials = materials or {}

    def error(self, key: str, message: str) -> CaseError:
        return CaseError(self.path, key, message)


def _describe(value: Any) -> str:
    return f"{value!r} ({type(value).__name__})"


def _number(ctx: Context, key: str, value: Any, meta: dict, want_int: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ctx.error(key, f"got {_describe(value)}; expected a number" + (f" in {meta.get('unit')}" if meta.get("unit") else ""))
    if want_int and not isinstance(value, int):
        raise ctx.error(key, f"got {value!r}; expected an integer")
    if not math.isfinite(value):
        raise ctx.error(key, f"got {value!r}; expected a finite number")
    pred, text = CHECKS[meta.get("check", "any")]
    if not pred(value):
        unit = f" {meta['unit']}" if meta.get("unit") else ""
        raise ctx.error(key, f"= {value!r}{unit}; expected {text}")
    return int(value) if want_int else float(value)


def _convert(ctx: Context, key: str, tp: Any, value: Any, meta: dict) -> Any:
    origin = get_origin(tp)
    if tp is float:
        return _number(ctx, key, value, meta)
    if tp is int:
        return _number(ctx, key, value, meta, want_int=True)
    if tp is bool:
        if not isinstance(value, bool):
            raise ctx.error(key, f"got {_describe(value)}; expected true or false")
        return value
    if tp is str:
        if not isinstance(value, str) or not value:
            raise ctx.error(key, f"got {_describe(value)}; expected a non-empty string")
        return value
    if tp is Material:
        if not isinstance(value, str):
            raise ctx.error(key, f"got {_describe(value)}; expected the name of a [materials.NAME] table")
        if value not in ctx.materials:
            raise ctx.error(key, f"material {value!r} is not defined; defined: {sorted(ctx.materials)}")
        return ctx.materials[value]
    if origin is Literal:
        choices = get_args(tp)
        if value not in choices:
            raise ctx.error(key, f"got {value!r}; expected one of {list(choices)}")
        return value
    if origin is tuple:
        args = get_args(tp)
        if not isinstance(value, (list, tuple)):
            raise ctx.error(key, f"got {_describe(value)}; expected an array")
        if len(args) == 2 and args[1] is Ellipsis:
            if len(value) == 0:
                raise ctx.error(key, "got an empty array; expected at least one entry")
            return tuple(_convert(ctx, f"{key}[{j}]", args[0], v, meta) for j, v in enumerate(value))
        if len(value) != len(args):
            raise ctx.error(key, f"got {len(value)} entries; expected {len(args)}")
        return tuple(_convert(ctx, f"{key}[{j}]", a, v, meta) for j, (a, v) in enumerate(zip(args, value)))
    if dataclasses.is_dataclass(tp):
        return build_section(ctx, key, tp, value)
    if origin is dict:
        kt, vt = get_args(tp)
        if not isinstance(value, dict):
            raise ctx.error(key, f"got {_describe(value)}; expected a table")
        return {k: _convert(ctx, f"{key}.{k}", vt, v, meta) for k, v in value.items()}
    if origin in (typing.Union, getattr(__import__("types"), "UnionType", None)):
        args = [a for a in get_args(tp) if a is not type(None)]
        if value is None:
            return None
        return _convert(ctx, key, args[0], value, meta)
    raise TypeError(f"unsupported case field type {tp!r} at {key}")  # programming error


def build_section(ctx: Context, key: str, cls: type, table: Any, extra: dict | None = None):
    """Validate ``table`` (a TOML table) into the frozen dataclass ``cls``.

    ``key`` is the dotted path of the table (for messages); ``extra`` supplies fields that do not
    come from the table (e.g. a material's name). Unknown keys and missing required keys raise
    :class:`CaseError`.
    """
    if not isinstance(table, dict):
        raise ctx.error(key, f"got {_describe(table)}; expected a table [{key}]")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    extra = extra or {}
    unknown = sorted(set(table) - set(fields))
    if unknown:
        prefix = f"{key}." if key else ""
        raise ctx.error(f"{prefix}{unknown[0]}", f"unknown key; expected one of {sorted(set(fields) - set(extra))}")
    kwargs = {}
    for name, f in fields.items():
        dotted = f"{key}.{name}" if key else name
        if name in extra:
            kwargs[name] = extra[name]
        elif name in table:
            kwargs[name] = _convert(ctx, dotted, hints[name], table[name], dict(f.metadata))
        elif f.default is MISSING and f.default_factory is MISSING:
            unit = f.metadata.get("unit")
            raise ctx.error(dotted, "required key is missing" + (f" (unit: {unit})" if unit else ""))
    try:
        return cls(**kwargs)
    except CaseError:
        raise
    except ValueError as exc:  # __post_init__ cross-field checks raise ValueError("key: message")
        msg = str(exc)
        sub, _, text = msg.partition(": ")
        return _raise(ctx, f"{key}.{sub}" if key and text else (key or sub), text or msg)


def _raise(ctx: Context, key: str, message: str):
    raise ctx.error(key, message)


def build_materials(ctx: Context, table: Any) -> dict[str, Material]:
    """``[materials.NAME]`` tables -> {name: Material}."""
    if not isinstance(table, dict) or not table:
        raise ctx.error("materials", "expected at least one [materials.NAME] table")
    return {name: build_section(ctx, f"materials.{name}", Material, t, extra={"name": name}) for name, t in table.items()}


def field_docs(cls: type) -> list[tuple[str, str, str]]:
    """(name, unit, doc) of every field of a case section, for generated documentation."""
    return [(f.name, f.metadata.get("unit", ""), f.metadata.get("doc", "")) for f in dataclasses.fields(cls)]


def build_sections(ctx: Context, raw: dict, sections: dict[str, type], optional=(), also_allowed=()) -> dict:
    """Validate the top-level tables of a case document: unknown sections and missing required ones
    raise :class:`CaseError`; every section in ``sections`` is built with :func:`build_section`
    (an optional one from an empty table, i.e. its defaults). ``also_allowed`` names tables that the
    caller builds itself (e.g. ``materials``)."""
    allowed = set(sections) | set(also_allowed)
    unknown = sorted(set(raw) - allowed)
    if unknown:
        raise ctx.error(unknown[0], f"unknown section; expected one of {sorted(allowed)}")
    parts = {}
    for name, cls in sections.items():
        table = raw.get(name, {} if name in optional else None)
        if table is None:
            raise ctx.error(name, f"required section [{name}] is missing")
        parts[name] = build_section(ctx, name, cls, table)
    return parts


class CaseVariants:
    """Mixin for case objects: ``case.with_params(**{"dotted.key": value})`` returns a re-validated variant."""

    def with_params(self, **dotted):
        from femcheck.case.registry import with_params
        return with_params(self, dotted)


@dataclasses.dataclass(frozen=True)
class CaseRecord(CaseVariants):
    """Base of every case object: its ``[meta]`` table (:class:`CaseMeta`, the first field of every kind), where it
    came from (``source``), the sha256 of its parsed document and the document as JSON (filled in by
    :func:`femcheck.case.registry.build_case`; keyword-only, so a kind's own required fields come next), and
    :meth:`with_params`."""

    meta: CaseMeta
    source: str = dataclasses.field(default="", kw_only=True)
    sha256: str = dataclasses.field(default="", kw_only=True)
    raw_json: str = dataclasses.field(default="", repr=False, kw_only=True)


def build_sectioned(cls: type, raw: dict, path, sections: dict[str, type], optional=()):
    """The common ``build()`` of a case kind made of a ``[materials]`` table and sections: validate them and
    construct ``cls(materials=..., **sections)`` (errors name the file and dotted key)."""
    ctx = Context(path)
    ctx.materials = build_materials(ctx, raw.get("materials"))
    parts = build_sections(ctx, raw, sections, optional, also_allowed=("materials",))
    return cls(materials=tuple(ctx.materials.values()), **parts)


@dataclasses.dataclass(frozen=True)
class CaseMeta:
    """The ``[meta]`` table every case kind shares: what the case is and where its numbers come from."""

    name: str = option("unnamed", doc="case name")
    kind: str = option("", doc="case kind (registry key: the module femcheck/case/<kind>.py)")
    version: int = quantity("-", default=1)
    reference: str = option("", doc="where the numbers come from")
    conventions: str = option("", doc="conventions document the case follows")
