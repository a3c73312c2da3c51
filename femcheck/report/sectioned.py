"""A report made of titled sections (paragraphs, tables, embedded PNG plots), written as Markdown and as one
self-contained HTML page (plots as base64), atomically. The diagnosis reports (device and serial robot) are
built on it; a section is ``(title, [("p", text) | ("table", header, rows) | ("img", png_name), ...])``."""
from __future__ import annotations

import base64
import html
from pathlib import Path

from femcheck.report.atomic import write_bytes_atomic, write_text_atomic

CSS = ("body{font-family:sans-serif;max-width:1200px;margin:auto}table{border-collapse:collapse;margin:8px 0}"
       "td,th{border:1px solid #bbb;padding:2px 6px;font-size:12px;text-align:right}img{max-width:100%}")


def md_table(header, rows) -> str:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def html_table(header, rows) -> str:
    h = "".join(f"<th>{html.escape(str(c))}</th>" for c in header)
    b = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><thead><tr>{h}</tr></thead><tbody>{b}</tbody></table>"


def write_sectioned_report(title: str, sections, pngs: dict[str, bytes], out_dir, page_title: str = "femcheck") -> list[Path]:
    """Write ``report.md``, ``report.html`` and the PNGs into ``out_dir``; returns the written paths."""
    out_dir = Path(out_dir)
    md = [f"# {title}", ""]
    body = [f"<h1>{html.escape(title)}</h1>"]
    for head, items in sections:
        md += [f"## {head}", ""]
        body.append(f"<h2>{html.escape(head)}</h2>")
        for it in items:
            if it[0] == "p":
                md += [it[1], ""]
                body.append(f"<p>{html.escape(it[1]).replace('**', '')}</p>")
            elif it[0] == "table":
                md += [md_table(it[1], it[2]), ""]
                body.append(html_table(it[1], it[2]))
            elif it[0] == "img":
                md += [f"![{it[1]}]({it[1]})", ""]
                body.append(f'<img alt="{it[1]}" src="data:image/png;base64,{base64.b64encode(pngs[it[1]]).decode("ascii")}"/>')
    page = (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(page_title)}</title>"
            f"<style>{CSS}</style></head><body>{''.join(body)}</body></html>")
    paths = [write_text_atomic(out_dir / "report.md", "\n".join(md)), write_text_atomic(out_dir / "report.html", page)]
    paths += [write_bytes_atomic(out_dir / n, b) for n, b in pngs.items()]
    return paths
