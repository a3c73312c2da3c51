"""Render a verification run: one writer from sections (title, rows, formats, note, images) to Markdown and HTML,
and the verdict files (``verdict.json``, JUnit XML).

A report is a list of :class:`Section` objects; :func:`render_markdown` and :func:`render_html` walk the same
list, so every table is described once (its CSV, if any, is written by the caller from the same rows).

Adding a section to the verify report is one call: ``sections.append(Section(title, rows, formats, note=...))``
in :func:`femcheck.verify.run.run_verify` (or in a function it calls); ``first=True`` puts it right after the
verdict (e.g. a coverage table). Adding a check is one :class:`~femcheck.verify.check.Check` appended to the
run's check list; the verdict, ``verdict.json`` and ``junit.xml`` list it.
"""
from __future__ import annotations

import dataclasses
import html
import json
from xml.sax.saxutils import quoteattr

from femcheck.report import tables
from femcheck.report.html_page import HtmlPage
from femcheck.verify.check import Check, verdict


@dataclasses.dataclass(frozen=True)
class Section:
    """One report section. ``rows``: table rows (dicts, same keys); ``formats``: column -> format spec;
    ``note``: a paragraph before the table; ``images``: (file name, PNG bytes, alt text) shown after it;
    ``pre``: preformatted lines (drift lists); ``first``: placed right after the verdict."""

    title: str
    rows: tuple = ()
    formats: dict = dataclasses.field(default_factory=dict)
    note: str = ""
    images: tuple = ()
    pre: str = ""
    first: bool = False
    extra_rows: tuple = ()          # a second table under the first (e.g. the meshes of a convergence study)


#: title of the section every report opens with
VERDICT_TITLE = "Verdict"


def ordered(sections: list[Section]) -> list[Section]:
    """The verdict, then the ``first`` sections in the order they were added, then the rest."""
    lead = [s for s in sections if s.title == VERDICT_TITLE]
    rest = [s for s in sections if s.title != VERDICT_TITLE]
    return lead + [s for s in rest if s.first] + [s for s in rest if not s.first]


def render_markdown(title: str, intro: str, sections: list[Section]) -> str:
    md = [f"# {title}\n\n", f"{intro}\n"]
    for s in ordered(sections):
        md.append(f"\n## {s.title}\n\n")
        if s.note:
            md.append(f"{s.note}\n\n")
        if s.rows:
            md.append(tables.to_markdown(list(s.rows), s.formats))
        if s.extra_rows:
            md += ["\n", tables.to_markdown(list(s.extra_rows))]
        if s.pre:
            md.append("\n```\n" + s.pre + "\n```\n")
        for name, _png, alt in s.images:
            md.append(f"\n![{alt}]({name})\n")
    return "".join(md)


def render_html(title: str, intro: str, sections: list[Section]) -> str:
    page = HtmlPage(title)
    page.paragraph(intro, "note")
    for s in ordered(sections):
        page.heading(s.title)
        if s.note:
            page.paragraph(s.note, "note")
        if s.rows:
            page.raw(tables.to_html(list(s.rows), s.formats))
        if s.extra_rows:
            page.raw(tables.to_html(list(s.extra_rows)))
        if s.pre:
            page.raw("<pre>" + html.escape(s.pre) + "</pre>")
        for _name, png, alt in s.images:
            page.image(png, alt)
    return page.render()


def verdict_section(checks: list[Check], worst: list[dict], seconds: float) -> Section:
    """The report's first section: the verdict line (:meth:`~femcheck.verify.check.Verdict.line`), every check
    (kind, status, detail, why skipped), the worst errors and the run time."""
    v = verdict(checks, worst)
    head = f"{v.line()}. Run time {seconds:.1f} s."
    if worst:
        head += " Worst mean analytical-FE errors: " + "; ".join(f"{w['table']} {w['direction']} {w['mean_error_pct']:.2f} %"
                                                               for w in worst) + "."
    rows = tuple({"check": c.name, "kind": c.kind, "status": c.status, "detail": c.detail + (f" (skipped: {c.reason})"
                                                                                             if c.reason else "")}
                 for c in checks)
    return Section(VERDICT_TITLE, rows, note=head, first=True)


def verdict_json(checks: list[Check], worst: list[dict], seconds: float) -> str:
    """``verdict.json``: the verdict (PASS/FAIL, summary line, failed checks, worst error), every check with its
    ``kind``, ``status`` and, when skipped, ``reason``; the worst errors and the run time."""
    return json.dumps({**verdict(checks, worst).as_json(), "seconds": round(seconds, 3),
                       "checks": [c.as_json() for c in checks], "worst_errors": worst}, indent=2) + "\n"


def junit_xml(checks: list[Check], seconds: float, suite: str = "femcheck verify") -> str:
    """JUnit XML (one testcase per check) for CI systems; a run that evaluated no check gets one failed testcase
    saying so."""
    if all(c.status == "skipped" for c in checks):
        # nothing was evaluated: a CI reading only the JUnit file must not see a green suite
        checks = list(checks) + [Check("at least one check evaluated", "threshold", "fail", verdict(checks).line())]
    n_fail = sum(c.status == "fail" for c in checks)
    n_skip = sum(c.status == "skipped" for c in checks)
    out = ['<?xml version="1.0" encoding="utf-8"?>',
           f'<testsuite name={quoteattr(suite)} tests="{len(checks)}" failures="{n_fail}" skipped="{n_skip}" '
           f'time="{seconds:.3f}">']
    for c in checks:
        case = f'  <testcase classname={quoteattr(suite)} name={quoteattr(c.name)}'
        if c.status == "fail":
            out.append(f"{case}><failure message={quoteattr(c.detail)}/></testcase>")
        elif c.status == "skipped":
            out.append(f"{case}><skipped message={quoteattr(c.reason)}/></testcase>")
        else:
            out.append(f"{case}/>")
    out.append("</testsuite>")
    return "\n".join(out) + "\n"
