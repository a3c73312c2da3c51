"""Plain table writers: rows (list of dicts) -> CSV text, Markdown text, HTML table.

A cell without a value (``None`` or NaN) is written as :data:`MISSING`, never as ``None``/``nan``; a column
whose missing values have a meaning carries it in ``explain`` (column -> text): the HTML cell gets it as a
tooltip and both writers add it as a footnote under the table. A missing value in a column without an
explanation stays a bare :data:`MISSING` (the report test flags it).
"""
from __future__ import annotations

import csv
import html
import io
import math

#: what a cell without a value shows
MISSING = "n/a"


def _fmt(v, digits: int = 4) -> str:
    if isinstance(v, float):
        return f"{v:.{digits}g}" if abs(v) < 1e-3 or abs(v) >= 1e5 else f"{v:.{digits}f}".rstrip("0").rstrip(".") if v != int(v) else f"{v:.1f}"
    return str(v)


def _missing(v) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v))


def format_spec(spec: str) -> str:
    """A format as ``str.format`` takes it: ``"{:.4g}"`` stays, a bare spec such as ``".4g"`` is wrapped."""
    return spec if "{" in spec else "{:" + spec + "}"


def to_csv(rows: list[dict]) -> str:
    """CSV with the keys of the first row as header (values written at full precision)."""
    if not rows:
        return ""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    return buf.getvalue()


def cells(rows: list[dict], formats: dict[str, str] | None = None) -> tuple[list[str], list[list[str]]]:
    """Column names and the formatted text of every cell; ``formats`` maps a column to a format spec
    (``"{:.3f}"`` or the bare ``".3f"``) applied to numbers (not to booleans), other values use the default
    short form; a missing value (None, NaN) is :data:`MISSING`."""
    specs = {c: format_spec(f) for c, f in (formats or {}).items()}
    cols = list(rows[0])

    def cell(c, v):
        if _missing(v):
            return MISSING
        if c in specs and isinstance(v, (int, float)) and not isinstance(v, bool):
            return specs[c].format(v)
        return _fmt(v)
    return cols, [[cell(c, r[c]) for c in cols] for r in rows]


def _notes(rows: list[dict], explain: dict[str, str] | None) -> list[str]:
    """Footnotes for the explained columns that do hold a missing value."""
    return [f"{MISSING} in {c}: {text}" for c, text in (explain or {}).items()
            if any(_missing(r.get(c)) for r in rows)]


def to_markdown(rows: list[dict], formats: dict[str, str] | None = None, explain: dict[str, str] | None = None) -> str:
    """GitHub Markdown table of the rows (see :func:`cells` for ``formats``, the module for ``explain``)."""
    if not rows:
        return "(no rows)\n"
    cols, body = cells(rows, formats)
    lines = ["| " + " | ".join(cols) + " |", "| " + " | ".join("---" for _ in cols) + " |"]
    lines += ["| " + " | ".join(r) + " |" for r in body]
    notes = _notes(rows, explain)
    return "\n".join(lines) + "\n" + ("".join(f"\n_{n}_\n" for n in notes))


def to_html(rows: list[dict], formats: dict[str, str] | None = None, explain: dict[str, str] | None = None) -> str:
    """An HTML <table> of the rows (see :func:`cells` for ``formats``, the module for ``explain``); an explained
    missing cell carries its explanation as ``title``."""
    if not rows:
        return "<p>(no rows)</p>"
    explain = explain or {}
    cols, body = cells(rows, formats)

    def td(c, v):
        if v == MISSING and c in explain:
            return f'<td class="missing" title="{html.escape(explain[c])}">{MISSING}</td>'
        return f"<td>{html.escape(v)}</td>"
    head = "".join(f"<th>{html.escape(c)}</th>" for c in cols)
    trs = "".join("<tr>" + "".join(td(c, v) for c, v in zip(cols, r)) + "</tr>" for r in body)
    notes = "".join(f'<p class="note">{html.escape(n)}</p>' for n in _notes(rows, explain))
    return f"<table><thead><tr>{head}</tr></thead><tbody>{trs}</tbody></table>{notes}"
