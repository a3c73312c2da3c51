"""Line-level edits of a case file's TOML text that keep everything else as the user wrote it.

The writers of corrected cases (``check-joints``, ``diagnose`` and ``identify`` with ``--extended-case``) copy the
input case and change a few keys. A TOML library would drop the comments that explain a case, so this module
edits lines: it sets one key of one table (or of the n-th table of an array of tables), inserting it where the
table has none, or appends a new table. Each edited line can carry a trailing comment (the 95 % interval and the
cause that set the value). :func:`checked` parses the result and compares every edited key with the value set,
so a text edit that TOML reads differently is caught before the file is written.

Limits: keys are bare (``[A-Za-z0-9_-]``); a table is found by its header line (``[model]``, ``[[joints]]``), not
through dotted keys or inline tables of a parent.
"""
from __future__ import annotations

import dataclasses
import math
import re
import tomllib

from femcheck.errors import FemcheckError

_HEADER = re.compile(r"^\s*(\[\[?)\s*([A-Za-z0-9_.\-\" ]+?)\s*\]\]?\s*(#.*)?$")


def toml_value(v) -> str:
    """TOML text of a scalar, array or inline table (floats as ``repr``: they read back bit for bit)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, int):
        return str(v)
    v = float(v)
    if not math.isfinite(v):
        raise FemcheckError(f"cannot write the non-finite value {v} into a case")
    return repr(v)


def _depth_change(line: str) -> int:
    """Bracket depth change of one line of a value, strings and the trailing comment left out."""
    depth, quote = 0, ""
    for ch in line:
        if quote:
            if ch == quote:
                quote = ""
        elif ch in "\"'":
            quote = ch
        elif ch == "#":
            break
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
    return depth


@dataclasses.dataclass(frozen=True)
class Edit:
    """One key set: ``table`` (dotted header name), ``index`` (n-th ``[[table]]``; None for ``[table]``)."""

    table: str
    key: str
    value: object
    comment: str = ""
    index: int | None = None

    def line(self) -> str:
        c = f"   # {self.comment}" if self.comment else ""
        return f"{self.key} = {toml_value(self.value)}{c}"


def _tables(lines: list[str]) -> list[tuple[str, bool, int, int]]:
    """(name, is_array, header line, end line exclusive) of every table header."""
    heads = []
    for i, l in enumerate(lines):
        m = _HEADER.match(l)
        if m and not l.lstrip().startswith("#"):
            heads.append((m.group(2).replace(" ", ""), m.group(1) == "[[", i))
    out = []
    for k, (name, arr, i) in enumerate(heads):
        end = heads[k + 1][2] if k + 1 < len(heads) else len(lines)
        out.append((name, arr, i, end))
    return out


def set_key(text: str, edit: Edit) -> str:
    """``text`` with ``edit.key`` of the table set to ``edit.value`` (replaced in place, multi-line values
    included; or inserted after the table's last key; or a new ``[table]`` appended when there is none)."""
    lines = text.split("\n")
    tabs = [t for t in _tables(lines) if t[0] == edit.table and t[1] == (edit.index is not None)]
    if edit.index is not None:
        if edit.index >= len(tabs):
            raise FemcheckError(f"[[{edit.table}]] number {edit.index + 1} is not in the case")
        tabs = [tabs[edit.index]]
    if not tabs:
        return text.rstrip("\n") + f"\n\n[{edit.table}]\n{edit.line()}\n"
    _, _, head, end = tabs[0]
    key_re = re.compile(rf"^\s*{re.escape(edit.key)}\s*=")
    last_key = head
    i = head + 1
    while i < end:
        l = lines[i]
        if key_re.match(l):
            j, depth = i, _depth_change(l.split("=", 1)[1])
            while depth > 0 and j + 1 < end:
                j += 1
                depth += _depth_change(lines[j])
            lines[i:j + 1] = [edit.line()]
            return "\n".join(lines)
        if l.strip() and not l.lstrip().startswith("#"):
            last_key = i
            depth = _depth_change(l.split("=", 1)[1]) if "=" in l else 0
            while depth > 0 and i + 1 < end:
                i += 1
                last_key = i
                depth += _depth_change(lines[i])
        i += 1
    lines.insert(last_key + 1, edit.line())
    return "\n".join(lines)


def append_table(text: str, table: str, items: dict, comment_lines=()) -> str:
    """``text`` plus a new ``[table]`` (``items`` {key: value} or {key: (value, comment)}), headed by comments."""
    out = ["", f"[{table}]"] + [f"# {c}" for c in comment_lines]
    for k, v in items.items():
        value, comment = v if isinstance(v, tuple) and len(v) == 2 and isinstance(v[1], str) else (v, "")
        out.append(Edit(table, k, value, comment).line())
    return text.rstrip("\n") + "\n" + "\n".join(out) + "\n"


def factor_table_edits(table: str, kinds, legs, held, new, low, high, source: str) -> list[Edit]:
    """One :class:`Edit` per element kind whose fitted factors ``new`` (L, K) move any leg: the written row is
    ``held * new`` (the case's own factors times the fitted ones), commented with each moved leg's value, its 95 %
    interval (``held * low`` .. ``held * high``) and ``source`` (the cause that set it). ``legs``: (L,) names."""
    edits = []
    for c, kind in enumerate(kinds):
        changed = [i for i in range(len(legs)) if new[i, c] != 1.0]
        if not changed:
            continue
        total = held[:, c] * new[:, c]
        parts = "; ".join(f"{legs[i]}: {total[i]:.4g} in [{held[i, c] * low[i, c]:.4g}, {held[i, c] * high[i, c]:.4g}]"
                          for i in changed)
        edits.append(Edit(table, kind, [float(v) for v in total], f"{parts} (95 %) from {source}"))
    return edits


def _lookup(doc: dict, e: Edit):
    node = doc
    for part in e.table.split("."):
        node = node[part]
    if e.index is not None:
        node = node[e.index]
    return node[e.key]


def checked(text: str, edits, source: str) -> str:
    """``text`` after parsing it and finding every edit's value there (else a :class:`FemcheckError`)."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise FemcheckError(f"{source}: the corrected case does not parse ({exc}); the input's layout defeats the "
                            "line-level edit, write the keys by hand") from None
    for e in edits:
        try:
            got = _lookup(doc, e)
        except (KeyError, IndexError, TypeError):
            got = None
        want = tomllib.loads(f"v = {toml_value(e.value)}")["v"]
        if got != want:
            raise FemcheckError(f"{source}: {e.table}{'' if e.index is None else f'[{e.index}]'}.{e.key} reads back as "
                                f"{got!r}, expected {want!r}; write the keys by hand")
    return text


def edited(text: str, edits, source: str) -> str:
    """``text`` with every :class:`Edit` applied in order, then :func:`checked`."""
    for e in edits:
        text = set_key(text, e)
    return checked(text, edits, source)
