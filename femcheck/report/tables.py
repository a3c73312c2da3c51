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


def to_markdown(rows: list[dict], formats: dict[str, str] | None = None) -> str:
    """GitHub Markdown table; ``formats`` maps a column to a format spec (e.g. ``"{:.3f}"``)."""
    if not rows:
        return "(no rows)\n"
    formats = formats or {}
    cols = list(rows[0])
    cell = lambda c, v: formats[c].format(v) if c in formats and isinstance(v, (int, float)) else _fmt(v)
    lines = ["| " + " | ".join(cols) + " |", "| " + " | ".join("---" for _ in cols) + " |"]
    lines += ["| " + " | ".join(cell(c, r[c]) for c in cols) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def to_html(rows: list[dict], formats: dict[str, str] | None = None) -> str:
    """An HTML <table> of the rows."""
    if not rows:
        return "<p>(no rows)</p>"
    formats = formats or {}
    cols = list(rows[0])
    cell = lambda c, v: formats[c].format(v) if c in formats and isinstance(v, (int, float)) else _fmt(v)
    head = "".join(f"<th>{html.escape(c)}</th>" for c in cols)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(cell(c, r[c]))}</td>" for c in cols) + "</tr>" for r in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"
