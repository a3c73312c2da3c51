"""Render a verification run: one writer from sections (title, rows, formats, note, images) to Markdown and HTML,
and the verdict files (``verdict.json``, JUnit XML).

A report is a list of :class:`Section` objects; :func:`render_markdown` and :func:`render_html` walk the same
list, so every table is described once (its CSV, if any, is written by the caller from the same rows).

The page opens with the verdict, then a table of contents (anchors), then the sections grouped by
:data:`PARTS` in the order a reader needs them: coverage, FE vs analytical errors, the joint table, the
diagnosis of the contact FE, mesh convergence, supporting tables and figures, and the raw deflections last
(folded). Adding a section to the verify report is one call:
``sections.append(Section(title, rows, formats, note=..., part="errors"))`` in
:func:`femcheck.verify.run.run_verify` (or in a function it calls). Adding a check is one :class:`~femcheck.verify.check.Check` appended to the
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


#: the parts of a report, in the order a reader needs them; every section belongs to one
PARTS = ("verdict", "coverage", "errors", "joints", "contact_diagnosis", "convergence", "supporting", "raw")
#: what a part is called in the table of contents
PART_TITLES = {"verdict": "Verdict", "coverage": "Coverage", "errors": "FE vs analytical errors",
               "joints": "Joint table", "contact_diagnosis": "Diagnosis of the contact FE",
               "convergence": "Mesh convergence", "supporting": "Supporting tables and figures",
               "raw": "Raw deflections"}
#: label put before the note of a table that no check reads
INFORMATIONAL = "Informational: no check reads this table."


@dataclasses.dataclass(frozen=True)
class Section:
    """One report section. ``rows``: table rows (dicts, same keys); ``formats``: column -> format spec;
    ``note``: a paragraph before the table; ``images``: (file name, PNG bytes, alt text) shown after it;
    ``pre``: preformatted lines (drift lists); ``part``: which of :data:`PARTS` it belongs to (``None``:
    "coverage" when ``first`` else "supporting"); ``informational``: no check reads its table (labelled so);
    ``explain``: column -> what a missing value there means; ``collapsed``: shown folded (``<details>``)."""

    title: str
    rows: tuple = ()
    formats: dict = dataclasses.field(default_factory=dict)
    note: str = ""
    images: tuple = ()
    pre: str = ""
    first: bool = False
    extra_rows: tuple = ()          # a second table under the first (e.g. the meshes of a convergence study)
    part: str | None = None
    informational: bool = False
    explain: dict = dataclasses.field(default_factory=dict)
    collapsed: bool = False

    @property
    def report_part(self) -> str:
        if self.title == VERDICT_TITLE:
            return "verdict"
        return self.part or ("coverage" if self.first else "supporting")

    @property
    def full_note(self) -> str:
        return " ".join(t for t in ((INFORMATIONAL if self.informational else ""), self.note) if t)


#: title of the section every report opens with
VERDICT_TITLE = "Verdict"


def ordered(sections: list[Section]) -> list[Section]:
    """Sections by :data:`PARTS` (the verdict first, raw deflections last), in the order added within a part."""
    return sorted(sections, key=lambda s: PARTS.index(s.report_part))


def anchor(index: int, section: Section) -> str:
    """The HTML/Markdown anchor of the ``index``-th section (ordered)."""
    return "verdict" if section.title == VERDICT_TITLE else f"s{index}"


def _contents(sections: list[Section]) -> list[tuple[str, list[tuple[str, str]]]]:
    """Table of contents: (part title, [(anchor, section title), ...]) for each part present."""
    out: list = []
    for i, s in enumerate(sections):
        title = PART_TITLES[s.report_part]
        if not out or out[-1][0] != title:
            out.append((title, []))
        out[-1][1].append((anchor(i, s), s.title))
    return out


def render_markdown(title: str, intro: str, sections: list[Section]) -> str:
    secs = ordered(sections)
    md = [f"# {title}\n\n", f"{intro}\n"]
    contents = ["\n**Contents**\n\n"]
    for part, items in _contents(secs):
        contents.append(f"- {part}\n")
        contents += [f"  - [{t}](#{a})\n" for a, t in items]
    for i, s in enumerate(secs):
        if i == 1 or (i == 0 and s.title != VERDICT_TITLE):
            md += contents
        md.append(f'\n<a id="{anchor(i, s)}"></a>\n\n## {s.title}\n\n')
        if s.full_note:
            md.append(f"{s.full_note}\n\n")
        body = []
        if s.rows:
            body.append(tables.to_markdown(list(s.rows), s.formats, s.explain))
        if s.extra_rows:
            body += ["\n", tables.to_markdown(list(s.extra_rows), explain=s.explain)]
        if s.pre:
            body.append("\n```\n" + s.pre + "\n```\n")
        for name, _png, alt in s.images:
            body.append(f"\n![{alt}]({name})\n")
        if s.collapsed:
            body = [f"<details><summary>{s.title}: {len(s.rows)} rows (click to open)</summary>\n\n", *body,
                    "\n</details>\n"]
        md += body
    return "".join(md)


def render_html(title: str, intro: str, sections: list[Section]) -> str:
    secs = ordered(sections)
    page = HtmlPage(title)
    page.paragraph(intro, "note")
    toc = "".join(f"<li>{html.escape(part)}<ul>" + "".join(f'<li><a href="#{a}">{html.escape(t)}</a></li>'
                                                            for a, t in items) + "</ul></li>"
                  for part, items in _contents(secs))
    for i, s in enumerate(secs):
        if i == 1 or (i == 0 and s.title != VERDICT_TITLE):
            # right after the verdict, so that the verdict stays above the fold
            page.raw(f'<nav id="contents"><h2>Contents</h2><ul>{toc}</ul></nav>')
        page.heading(s.title, anchor=anchor(i, s))
        if s.full_note:
            page.paragraph(s.full_note, "note")
        if s.collapsed:
            page.raw(f"<details><summary>{html.escape(s.title)}: {len(s.rows)} rows (click to open)</summary>")
        if s.rows:
            page.raw(tables.to_html(list(s.rows), s.formats, s.explain))
        if s.extra_rows:
            page.raw(tables.to_html(list(s.extra_rows), explain=s.explain))
        if s.pre:
            page.raw("<pre>" + html.escape(s.pre) + "</pre>")
        for _name, png, alt in s.images:
            page.image(png, alt)
        if s.collapsed:
            page.raw("</details>")
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
