"""Plain table writers: rows (list of dicts) -> CSV text, Markdown text, HTML table."""
from __future__ import annotations

import csv
import html
import io


def _fmt(v, digits: int = 4) -> str:
    if isinstance(v, float):
        return f"{v:.{digits}g}" if abs(v) < 1e-3 or abs(v) >= 1e5 else f"{v:.{digits}f}".rstrip("0").rstrip(".") if v != int(v) else f"{v:.1f}"
    return str(v)


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
    (e.g. ``"{:.3f}"``) applied to numbers, other values use the default short form."""
    formats = formats or {}
    cols = list(rows[0])
    cell = lambda c, v: formats[c].format(v) if c in formats and isinstance(v, (int, float)) else _fmt(v)
    return cols, [[cell(c, r[c]) for c in cols] for r in rows]


def to_markdown(rows: list[dict], formats: dict[str, str] | None = None) -> str:
    """GitHub Markdown table of the rows (see :func:`cells` for ``formats``)."""
    if not rows:
        return "(no rows)\n"
    cols, body = cells(rows, formats)
    lines = ["| " + " | ".join(cols) + " |", "| " + " | ".join("---" for _ in cols) + " |"]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in body]) + "\n"


def to_html(rows: list[dict], formats: dict[str, str] | None = None) -> str:
    """An HTML <table> of the rows (see :func:`cells` for ``formats``)."""
    if not rows:
        return "<p>(no rows)</p>"
    cols, body = cells(rows, formats)
    head = "".join(f"<th>{html.escape(c)}</th>" for c in cols)
    trs = "".join("<tr>" + "".join(f"<td>{html.escape(v)}</td>" for v in r) + "</tr>" for r in body)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{trs}</tbody></table>"
