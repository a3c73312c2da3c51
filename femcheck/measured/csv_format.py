"""Measured-data CSV: one row per dial reading.

Columns (header required, any order)::

    point, direction, trial, phase, load_N, fx_N, fy_N, fz_N, dx_mm, dy_mm, dz_mm
    [, mx_Nm, my_Nm, mz_Nm] [, rx_rad, ry_rad, rz_rad]

``point``: P0..P8 (or a pose id of the case's pose table); ``direction``: ``+x, -x, +y, -y, +z, -z`` or a
named load case (an identifier; its direction is then the applied force); ``trial``: integer >= 1;
``phase``: ``preload`` | ``total`` | ``unload`` | ``sweep``; ``load_N``: signed force magnitude (N) along the
direction; ``fx_N..fz_N``: the applied TCP force in U (N), which for an axis direction must equal
``load_N`` times the axis; ``dx_mm..dz_mm``: dial readings of the TCP translation (mm, dials zeroed unloaded).

Lines starting with ``#`` before the header carry metadata as ``# key: value`` (for example
``# case_sha256: <hex>``, written by ``femcheck experiment simulate``); ``diagnose`` compares them with the
case it is given. The file is opened read-only and never modified. Every error names the file, the row
(1-based: the header is row 1 when there are no metadata lines, and every line counts) and the column.
Internally everything is SI (m, N).
"""
from __future__ import annotations

import csv
import dataclasses
import io
import math
import re
from pathlib import Path

import numpy as np

from femcheck.errors import MeasuredDataError

COLUMNS = ("point", "direction", "trial", "phase", "load_N", "fx_N", "fy_N", "fz_N", "dx_mm", "dy_mm", "dz_mm")
OPTIONAL_COLUMNS = ("mx_Nm", "my_Nm", "mz_Nm", "rx_rad", "ry_rad", "rz_rad")
PHASES = ("preload", "total", "unload", "sweep")
AXIS_DIRECTIONS = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1)}
_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_.\-]*$")
#: force components must match load_N * axis to this absolute tolerance (N): a 4-digit force print
FORCE_TOL_N = 1e-3


@dataclasses.dataclass(frozen=True)
class MeasuredData:
    """Validated rows of a measured-data CSV (SI).

    point, direction, phase: (r,) str arrays; trial: (r,) int; load_N: (r,) N; force: (r, 3) N;
    disp: (r, 3) m (dial readings); moment: (r, 3) N m or None; rotation: (r, 3) rad or None;
    row: (r,) 1-based file row numbers (header = 1), for error messages downstream.
    """

    source: str
    point: np.ndarray
    direction: np.ndarray
    trial: np.ndarray
    phase: np.ndarray
    load_N: np.ndarray
    force: np.ndarray
    disp: np.ndarray
    row: np.ndarray
    moment: np.ndarray | None = None
    rotation: np.ndarray | None = None
    #: ``# key: value`` metadata lines before the header
    meta: dict = dataclasses.field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.point)

    def error(self, index: int, column: str | None, message: str) -> MeasuredDataError:
        """A MeasuredDataError naming the file row of data row ``index``."""
        return MeasuredDataError(self.source, int(self.row[index]), column, message)


def _number(path, rownum, col, text) -> float:
    try:
        v = float(text)
    except (TypeError, ValueError):
        raise MeasuredDataError(path, rownum, col, f"{text!r} is not a number") from None
    if not math.isfinite(v):
        raise MeasuredDataError(path, rownum, col, f"{text!r} is not a finite number")
    return v


def parse_measured_csv(text: str, source: str = "<memory>") -> MeasuredData:
    """Parse and validate CSV ``text`` (see module docstring); ``source`` names it in errors."""
    lines = text.splitlines(keepends=True)
    meta: dict[str, str] = {}
    skipped = 0
    while skipped < len(lines) and lines[skipped].lstrip().startswith("#"):
        key, sep, value = lines[skipped].lstrip()[1:].partition(":")
        if sep and key.strip():
            meta[key.strip()] = value.strip()
        skipped += 1
    reader = csv.reader(io.StringIO("".join(lines[skipped:])))
    try:
        header = [h.strip() for h in next(reader)]
    except StopIteration:
        raise MeasuredDataError(source, None, None, "empty file; expected a header " + ", ".join(COLUMNS)) from None
    for c in COLUMNS:
        if c not in header:
            raise MeasuredDataError(source, 1, c, f"missing column; the header must contain {', '.join(COLUMNS)}")
    for c in header:
        if c not in COLUMNS and c not in OPTIONAL_COLUMNS:
            raise MeasuredDataError(source, 1, c, f"unknown column; expected {', '.join(COLUMNS + OPTIONAL_COLUMNS)}")
    if len(set(header)) != len(header):
        dup = next(c for c in header if header.count(c) > 1)
        raise MeasuredDataError(source, 1, dup, "column appears twice")
    for group in (OPTIONAL_COLUMNS[:3], OPTIONAL_COLUMNS[3:]):
        present = [c for c in group if c in header]
        if present and len(present) != 3:
            missing = next(c for c in group if c not in header)
            raise MeasuredDataError(source, 1, missing, f"optional columns {', '.join(group)} come as a set of three")
    col = {c: header.index(c) for c in header}
    has_m, has_r = "mx_Nm" in col, "rx_rad" in col
    rows = {k: [] for k in ("point", "direction", "trial", "phase", "load", "force", "disp", "moment", "rotation", "row")}
    seen: dict[tuple, int] = {}
    for rownum, rec in enumerate(reader, start=2 + skipped):
        if not rec or all(not f.strip() for f in rec):
            continue
        if len(rec) != len(header):
            raise MeasuredDataError(source, rownum, None, f"{len(rec)} fields; the header has {len(header)}")
        f = {c: rec[i].strip() for c, i in col.items()}
        point = f["point"]
        if not _IDENT.match(point):
            raise MeasuredDataError(source, rownum, "point", f"{point!r}; expected P0..P8 or a pose id (letters, digits, _)")
        direction = f["direction"]
        if direction not in AXIS_DIRECTIONS and not _IDENT.match(direction):
            raise MeasuredDataError(source, rownum, "direction",
                                    f"{direction!r}; expected +x, -x, +y, -y, +z, -z or a named load case")
        try:
            trial = int(f["trial"])
        except ValueError:
            raise MeasuredDataError(source, rownum, "trial", f"{f['trial']!r}; expected an integer >= 1") from None
        if trial < 1:
            raise MeasuredDataError(source, rownum, "trial", f"{trial}; expected an integer >= 1")
        phase = f["phase"]
        if phase not in PHASES:
            raise MeasuredDataError(source, rownum, "phase", f"{phase!r}; expected one of {', '.join(PHASES)}")
        load = _number(source, rownum, "load_N", f["load_N"])
        force = np.array([_number(source, rownum, c, f[c]) for c in ("fx_N", "fy_N", "fz_N")])
        disp = np.array([_number(source, rownum, c, f[c]) for c in ("dx_mm", "dy_mm", "dz_mm")]) * 1e-3
        if direction in AXIS_DIRECTIONS:
            expect = load * np.asarray(AXIS_DIRECTIONS[direction], float)
            bad = np.flatnonzero(np.abs(force - expect) > FORCE_TOL_N)
            if bad.size:
                c = ("fx_N", "fy_N", "fz_N")[bad[0]]
                raise MeasuredDataError(source, rownum, c, f"{force[bad[0]]:g} N; direction {direction} with load_N = {load:g} "
                                        f"requires {expect[bad[0]]:g} N")
        elif abs(np.linalg.norm(force) - abs(load)) > FORCE_TOL_N * max(1.0, abs(load)):
            raise MeasuredDataError(source, rownum, "load_N", f"{load:g} N but |(fx, fy, fz)| = {np.linalg.norm(force):g} N")
        key = (point, direction, trial, phase, round(load, 6))
        if key in seen:
            raise MeasuredDataError(source, rownum, "phase", f"duplicate reading (same point, direction, trial, phase and load "
                                    f"as row {seen[key]})")
        seen[key] = rownum
        rows["point"].append(point); rows["direction"].append(direction); rows["trial"].append(trial)
        rows["phase"].append(phase); rows["load"].append(load); rows["force"].append(force); rows["disp"].append(disp)
        rows["row"].append(rownum)
        if has_m:
            rows["moment"].append([_number(source, rownum, c, f[c]) for c in OPTIONAL_COLUMNS[:3]])
        if has_r:
            rows["rotation"].append([_number(source, rownum, c, f[c]) for c in OPTIONAL_COLUMNS[3:]])
    if not rows["point"]:
        raise MeasuredDataError(source, None, None, "no data rows after the header")
    return MeasuredData(
        source=source, point=np.array(rows["point"], dtype=object), direction=np.array(rows["direction"], dtype=object),
        trial=np.array(rows["trial"], dtype=int), phase=np.array(rows["phase"], dtype=object),
        load_N=np.array(rows["load"], dtype=float), force=np.array(rows["force"], dtype=float).reshape(-1, 3),
        disp=np.array(rows["disp"], dtype=float).reshape(-1, 3), row=np.array(rows["row"], dtype=int),
        moment=np.array(rows["moment"], dtype=float) if has_m else None,
        rotation=np.array(rows["rotation"], dtype=float) if has_r else None, meta=meta)


def read_data_text(path) -> str:
    """The text of a measured-data file (read-only; a byte-order mark dropped); a missing, binary or directory
    path raises :class:`MeasuredDataError` naming it."""
    p = Path(path)
    try:
        return p.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise MeasuredDataError(path, None, None, "file not found") from None
    except UnicodeDecodeError as exc:
        raise MeasuredDataError(path, None, None, f"not UTF-8 text ({exc.reason})") from None
    except IsADirectoryError:
        raise MeasuredDataError(path, None, None, "is a directory; expected a CSV file") from None


def read_table_rows(path, columns, error: type[Exception]) -> list[dict]:
    """The rows (one dict per line, keyed by the header) of the CSV table at ``path``, whose header must hold every
    name of ``columns``: for the tables read by the identification commands (``DATA.csv``, the HISS readings). An
    unreadable file or a missing column raises ``error`` with one line naming the file and what was expected."""
    try:
        with open(path, newline="") as fh:
            rows = list(csv.DictReader(fh))
    except OSError as e:
        raise error(f"{path}: cannot read ({e.strerror})") from None
    if not rows or any(c not in rows[0] for c in columns):
        raise error(f"{path}: expected header columns {','.join(columns)}")
    return rows


def read_measured_csv(path) -> MeasuredData:
    """Read and validate a measured-data CSV file (opened read-only; never modified)."""
    return parse_measured_csv(read_data_text(path), str(path))


def format_measured_csv(point, direction, trial, phase, load_N, force, disp, resolution_m: float = 1e-5,
                        meta: dict | None = None) -> str:
    """CSV text in the format above; ``disp`` (r, 3) in m is printed in mm with the digits the resolution needs;
    ``meta`` becomes ``# key: value`` lines before the header."""
    digits = max(0, int(math.ceil(-math.log10(resolution_m * 1e3) - 1e-9))) + 1 if resolution_m > 0 else 6
    out = io.StringIO()
    for key, value in (meta or {}).items():
        out.write(f"# {key}: {value}\n")
    w = csv.writer(out, lineterminator="\n")
    w.writerow(COLUMNS)
    for i in range(len(point)):
        w.writerow([point[i], direction[i], int(trial[i]), phase[i], f"{load_N[i]:.4g}",
                    *(f"{v:.4g}" if v != 0 else "0" for v in force[i]), *(f"{v * 1e3:.{digits}f}" for v in disp[i])])
    return out.getvalue()


def write_measured_csv(path, *args, **kw) -> Path:
    """Write :func:`format_measured_csv` atomically to ``path``."""
    from femcheck.report.atomic import write_text_atomic
    return write_text_atomic(path, format_measured_csv(*args, **kw))


def concat_measured(*parts: MeasuredData, source: str | None = None) -> MeasuredData:
    """The rows of several measured datasets as one (e.g. a campaign and the follow-up a plan asked for).
    Optional moment / rotation columns are kept only when every part has them; ``row`` is renumbered."""
    if not parts:
        raise ValueError("concat_measured needs at least one dataset")
    cat = lambda f: np.concatenate([getattr(p, f) for p in parts])
    opt = lambda f: cat(f) if all(getattr(p, f) is not None for p in parts) else None
    n = sum(len(p) for p in parts)
    return MeasuredData(source=source or " + ".join(p.source for p in parts), point=cat("point"),
                        direction=cat("direction"), trial=cat("trial"), phase=cat("phase"), load_N=cat("load_N"),
                        force=cat("force"), disp=cat("disp"), row=np.arange(2, n + 2), moment=opt("moment"),
                        rotation=opt("rotation"), meta=dict(parts[0].meta))
