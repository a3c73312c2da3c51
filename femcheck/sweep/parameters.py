"""Swept parameters: ``KEY=LO:HI[:N|log]`` on the command line, validated against the case.

``KEY`` is any continuous (float) quantity of the case by its dotted path, e.g.
``guideway.width_radial_m`` or ``materials.aluminium.E_Pa``. ``LO:HI`` is the closed range in the
key's SI unit (the unit the case file uses). The optional third field is either ``N`` (number of
grid levels for ``--design grid``) or ``log`` (sample ln p uniformly instead of p); both may be
given as ``LO:HI:N:log``.

Each parameter is classified by how the analytical model can vary it:

- ``array``: an element parameter that :func:`femcheck.chain.device_parameters` accepts as an (n,)
  array, so all samples x points are evaluated in one vectorized call;
- ``variant``: anything else (geometry that moves joints, loads, densities, ...): the evaluator builds
  a re-validated case variant with ``case.with_params`` per distinct value set (in chunks).

Errors (:class:`femcheck.errors.CaseError`) name the key and the offending value.
"""
from __future__ import annotations

import dataclasses
import logging
import math
import typing

import numpy as np

from femcheck.errors import CaseError

log = logging.getLogger(__name__)

#: grid levels per parameter when neither ``:N`` nor ``--samples`` says otherwise
DEFAULT_GRID_LEVELS = 5


@dataclasses.dataclass(frozen=True)
class ParameterRange:
    """One swept case quantity.

    key: dotted case key; lo, hi: range ends in the key's SI unit (lo < hi); levels: grid levels
    (None = design default); log: sample ln(p) uniformly (needs lo > 0); kind: "array" or "variant";
    unit: the key's unit as declared in the case schema; nominal: the case's own value.
    """

    key: str
    lo: float
    hi: float
    levels: int | None = None
    log: bool = False
    kind: str = "array"
    unit: str = ""
    nominal: float = float("nan")

    def from_unit(self, u: np.ndarray) -> np.ndarray:
        """Map u in [0, 1] to the range: p = lo + u (hi - lo), or lo (hi/lo)^u for ``log``."""
        u = np.asarray(u, dtype=float)
        if self.log:
            return np.exp(np.log(self.lo) + u * (np.log(self.hi) - np.log(self.lo)))
        return self.lo + u * (self.hi - self.lo)

    def grid(self, levels: int) -> np.ndarray:
        """``levels`` equally spaced values (geometrically for ``log``), ends included."""
        if levels <= 1:
            return np.array([self.from_unit(0.5)])
        return np.geomspace(self.lo, self.hi, levels) if self.log else np.linspace(self.lo, self.hi, levels)

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)

    @property
    def column(self) -> str:
        """Column name in the result table (``p:`` + dotted key)."""
        return f"p:{self.key}"


def parse_param(text: str, where: str = "--param") -> ParameterRange:
    """Parse ``KEY=LO:HI[:N|log]`` (syntax only; see :func:`validate_ranges` for the case checks)."""
    key, sep, rng = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise CaseError(where, text, "expected KEY=LO:HI[:N|log], e.g. guideway.width_radial_m=0.010:0.020:5")
    fields = [f.strip() for f in rng.split(":")]
    if len(fields) < 2 or len(fields) > 4:
        raise CaseError(where, key, f"range {rng!r}: expected LO:HI[:N|log]")
    try:
        lo, hi = float(fields[0]), float(fields[1])
    except ValueError:
        raise CaseError(where, key, f"range {rng!r}: LO and HI must be numbers (SI unit of the key)") from None
    levels, use_log = None, False
    for extra in fields[2:]:
        if extra.lower() == "log":
            use_log = True
            continue
        try:
            levels = int(extra)
        except ValueError:
            raise CaseError(where, key, f"range {rng!r}: third field {extra!r} must be a level count N or 'log'") from None
        if levels < 1:
            raise CaseError(where, key, f"range {rng!r}: level count N = {levels}; expected >= 1")
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise CaseError(where, key, f"range {rng!r}: LO and HI must be finite")
    if not lo < hi:
        raise CaseError(where, key, f"range {rng!r}: LO = {lo:g} must be smaller than HI = {hi:g}")
    if use_log and lo <= 0:
        raise CaseError(where, key, f"range {rng!r}: a log range needs LO > 0, got {lo:g}")
    return ParameterRange(key=key, lo=lo, hi=hi, levels=levels, log=use_log)


def _field_of(case, key: str):
    """(value, unit) of the float quantity ``key`` of ``case``; CaseError naming the key otherwise."""
    parts = key.split(".")
    if parts[0] == "materials":
        if len(parts) != 3:
            raise CaseError(case.source, key, "expected materials.NAME.QUANTITY, e.g. materials.aluminium.E_Pa")
        try:
            obj = case.material(parts[1])
        except KeyError:
            names = [m.name for m in case.materials]
            raise CaseError(case.source, key, f"material {parts[1]!r} is not defined; defined: {names}") from None
        name = parts[2]
    elif len(parts) > 2 and all(p.isdigit() for p in parts[1:-1:2]):
        # an entry of an array of tables (parallel_device legs): legs.0.links.1.outer_diameter_m
        obj = case
        for name_, index in zip(parts[:-1:2], parts[1:-1:2]):
            seq = getattr(obj, name_, None)
            if not isinstance(seq, tuple) or int(index) >= len(seq):
                raise CaseError(case.source, key, f"no entry {name_}[{index}] in the case")
            obj = seq[int(index)]
        name = parts[-1]
    else:
        if len(parts) != 2:
            raise CaseError(case.source, key, "expected SECTION.KEY, e.g. guideway.width_radial_m")
        obj = getattr(case, parts[0], None)
        if obj is None or not dataclasses.is_dataclass(obj) or isinstance(obj, type):
            sections = sorted(f.name for f in dataclasses.fields(case)
                              if dataclasses.is_dataclass(getattr(case, f.name)) and f.name != "meta")
            raise CaseError(case.source, key, f"no section [{parts[0]}] in the case; sections: {sections}")
        name = parts[1]
    fields = {f.name: f for f in dataclasses.fields(obj)}
    if name not in fields:
        numeric = sorted(n for n, f in fields.items() if typing.get_type_hints(type(obj)).get(n) is float)
        raise CaseError(case.source, key, f"unknown key; numeric keys of this table: {numeric}")
    hint = typing.get_type_hints(type(obj)).get(name)
    if not (hint is float or (hint == float | None and isinstance(getattr(obj, name), float))):
        raise CaseError(case.source, key, "not a continuous quantity (only float keys can be swept)")
    return float(getattr(obj, name)), fields[name].metadata.get("unit", "")


def _reason(exc: CaseError) -> str:
    """The message of a CaseError without its "file: key: " prefix (the caller names both)."""
    text = str(exc)
    prefix = f"{exc.path}: {exc.key}: " if exc.key else f"{exc.path}: "
    return f"{exc.key}: {text[len(prefix):]}" if text.startswith(prefix) and exc.key else text


def classify(case, key: str) -> str:
    """"array" if :func:`femcheck.chain.device_parameters` takes ``key`` as an array, else "variant"."""
    from femcheck.chain import device_parameters
    value, _ = _field_of(case, key)
    if getattr(case, "kind", "haptic_6psu") != "haptic_6psu":
        return "variant"  # only the 6-PSU chain model (femcheck.chain) takes element parameters as arrays
    try:
        device_parameters(case, {key: np.array([value])})
    except ValueError:
        return "variant"
    return "array"


def validate_ranges(case, ranges: list[ParameterRange]) -> list[ParameterRange]:
    """Check every range against ``case`` and return them completed (kind, unit, nominal).

    A key that is not a float quantity of the case, a duplicate key, or a range end that the case
    validation rejects (e.g. a negative diameter, a seat radius smaller than the ball) raises
    :class:`CaseError` naming the key and the value.
    """
    if not ranges:
        raise CaseError(case.source, "--param", "no parameter to sweep; give at least one --param KEY=LO:HI")
    seen = set()
    out = []
    for r in ranges:
        if r.key in seen:
            raise CaseError(case.source, r.key, "given twice")
        seen.add(r.key)
        nominal, unit = _field_of(case, r.key)
        for end, value in (("LO", r.lo), ("HI", r.hi)):
            try:
                case.with_params(**{r.key: value})
            except CaseError as exc:
                raise CaseError(case.source, r.key, f"range end {end} = {value:g} {unit} is invalid for the case: "
                                f"{_reason(exc)}") from None
        out.append(dataclasses.replace(r, kind=classify(case, r.key), unit=unit, nominal=nominal))
    _check_corners(case, out)
    log.debug("swept parameters: %s", [(r.key, r.kind) for r in out])
    return out


#: up to this many parameters, every corner of the box is validated (cross-key checks such as inner < outer)
MAX_CORNER_CHECK_DIM = 10


def _check_corners(case, ranges: list[ParameterRange]) -> None:
    """Validate the case at every corner of the parameter box (cross-key constraints of the schema,
    e.g. ``inner_diameter_m < outer_diameter_m``, are monotone, so the corners bound the box)."""
    d = len(ranges)
    if d < 2 or d > MAX_CORNER_CHECK_DIM:
        return
    for corner in range(2**d):
        values = {r.key: (r.hi if corner >> j & 1 else r.lo) for j, r in enumerate(ranges)}
        try:
            case.with_params(**values)
        except CaseError as exc:
            where = ", ".join(f"{k}={v:g}" for k, v in values.items())
            raise CaseError(case.source, exc.key or ranges[0].key,
                            f"the corner ({where}) of the parameter box is invalid: {_reason(exc)}") from None


def parse_params(case, texts: list[str]) -> list[ParameterRange]:
    """Parse and validate the ``--param`` texts against ``case``."""
    return validate_ranges(case, [parse_param(t) for t in texts])
