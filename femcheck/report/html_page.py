"""A self-contained HTML page (inline CSS, PNGs embedded as base64): reports open anywhere, offline."""
from __future__ import annotations

import base64
import html

_CSS = """body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;margin:1em 0;font-size:0.9em}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}
th{background:#eee}h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em}img{max-width:100%}.note{color:#555}
code{background:#f4f4f4;padding:1px 4px}nav ul{margin:0.2em 0}nav{font-size:0.9em}
td.missing{color:#777}summary{cursor:pointer;color:#345}"""


class HtmlPage:
    """Collects sections and renders one HTML document."""

    def __init__(self, title: str):
        self.title = title
        self.parts: list[str] = []

    def heading(self, text: str, level: int = 2, anchor: str = "") -> "HtmlPage":
        ident = f' id="{html.escape(anchor)}"' if anchor else ""
        self.parts.append(f"<h{level}{ident}>{html.escape(text)}</h{level}>")
        return self

    def paragraph(self, text: str, cls: str = "") -> "HtmlPage":
        c = f' class="{cls}"' if cls else ""
        self.parts.append(f"<p{c}>{html.escape(text)}</p>")
        return self

    def raw(self, fragment: str) -> "HtmlPage":
        self.parts.append(fragment)
        return self

    def image(self, png: bytes, alt: str) -> "HtmlPage":
        data = base64.b64encode(png).decode("ascii")
        self.parts.append(f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}"/>')
        return self

    def render(self) -> str:
        return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(self.title)}</title>"
                f"<style>{_CSS}</style></head><body><h1>{html.escape(self.title)}</h1>{''.join(self.parts)}</body></html>\n")
