"""The verify report in a real headless browser: every image loads, the verdict is visible without
scrolling, no console error, and no table cell holds a bare format code (``.4g``, ``{:+.1f}``), ``None`` or
``nan``, nor an unexplained missing value (``n/a`` without a ``title``). Skipped with a reason when no Chromium is installed
(Debian/Ubuntu: ``apt-get install chromium``; see README, optional tools).

A small probe script is put into a copy of report.html (the report itself has no scripts): it records error
events from the start (capture phase, so failed images count), and on ``load`` writes what it measured into
the DOM, which ``chromium --headless --dump-dom`` prints.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import ROOT
from femcheck.verify.render import Section, render_html

VIEWPORT = (1280, 800)
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
         "--disable-sync", "--no-first-run", "--enable-logging=stderr", "--v=0",
         f"--window-size={VIEWPORT[0]},{VIEWPORT[1]}", "--virtual-time-budget=5000", "--dump-dom"]

PROBE = """<script>
window.__errors = [];
window.addEventListener('error', function (e) {
  var t = e.target;
  window.__errors.push(t && t.tagName ? ('resource ' + t.tagName + ' failed') : String(e.message));
}, true);
['error'].forEach(function (k) { var f = console[k]; console[k] = function () {
  window.__errors.push('console.' + k + ': ' + Array.prototype.join.call(arguments, ' ')); f.apply(console, arguments); }; });
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var heads = Array.prototype.slice.call(document.querySelectorAll('h2'));
  var v = heads.filter(function (h) { return h.textContent.trim() === 'Verdict'; })[0];
  var note = v ? v.nextElementSibling : null;
  var bare = /^([+-]?\\.\\d+[a-zA-Z%]|\\{[^}]*\\}|None|nan|NaN)$/;
  var cells = Array.prototype.slice.call(document.querySelectorAll('td'));
  var badCells = cells.filter(function (c) {
    var t = c.textContent.trim();
    return bare.test(t) || (t === 'n/a' && !c.title);
  }).map(function (c) { return c.textContent.trim(); });
  var out = {images: imgs.length, cells: cells.length, bad_cells: badCells,
             anchors_ok: Array.prototype.slice.call(document.querySelectorAll('nav a')).every(function (a) {
               return document.getElementById(a.getAttribute('href').slice(1)) !== null; }),
             broken: imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); }).map(function (i) { return i.alt; }),
             verdict_bottom: note ? note.getBoundingClientRect().bottom : null, verdict_text: note ? note.textContent : '',
             viewport: window.innerHeight, errors: window.__errors};
  var pre = document.createElement('pre'); pre.id = '__probe__'; pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
});
</script>"""


def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome"):
        path = shutil.which(name)
        if path:
            return path
    return "/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else None


def _probe(html_text: str, tmp_path) -> dict:
    browser = _chromium()
    if browser is None:
        pytest.skip("no Chromium on this machine (apt-get install chromium; README, optional tools)")
    page = tmp_path / "probe.html"
    page.write_text(html_text.replace("<head>", "<head>" + PROBE, 1), encoding="utf-8")
    profile = tmp_path / "profile"
    profile.mkdir()
    res = subprocess.run([browser, *FLAGS, f"--user-data-dir={profile}", page.as_uri()], capture_output=True,
                         text=True, timeout=120)
    m = re.search(r'<pre id="__probe__">(.*?)</pre>', res.stdout, re.S)
    assert m, f"no probe output; chromium rc {res.returncode}: {res.stderr[-2000:]}"
    out = json.loads(m.group(1).replace("&quot;", '"').replace("&amp;", "&").replace("&lt;", "<").replace("&gt;", ">"))
    # console errors the page could not see (logged by the browser itself)
    out["errors"] += [ln for ln in res.stderr.splitlines() if "CONSOLE" in ln and ("ERROR" in ln or "Uncaught" in ln)]
    return out


@pytest.mark.slow  # ~13 s: an analytical verify run (plots) plus a browser start
def test_verify_report_in_headless_browser(tmp_path, case):
    from femcheck.verify.run import run_verify
    # --check against the committed baseline: a run with no evaluated check would (rightly) not be a PASS
    run = run_verify(case, tmp_path / "run", points=("P0", "P7"), check=True,
                     baseline_path=ROOT / "reports" / "baseline" / "analytical.json")
    out = _probe((tmp_path / "run" / "report.html").read_text(encoding="utf-8"), tmp_path)
    assert out["images"] >= 4 and out["broken"] == [], out           # contributions + 3 deflection plots, all decoded
    assert out["verdict_bottom"] is not None and out["verdict_bottom"] <= out["viewport"], out  # above the fold
    assert out["verdict_text"].startswith("PASS"), out
    assert out["errors"] == [], out
    assert out["cells"] > 100 and out["bad_cells"] == [], out["bad_cells"]   # every number formatted
    assert out["anchors_ok"], out                                          # every contents link lands
    assert run.checks and all(c.status in ("pass", "skipped") for c in run.checks)


def test_browser_probe_sees_a_broken_image_and_a_late_verdict(tmp_path):
    """The probe can fail: a PNG that does not decode and a verdict pushed below the fold are both caught."""
    filler = [Section(f"filler {k}", tuple({"a": i, "b": i * 2.0} for i in range(40))) for k in range(4)]
    bad = Section("broken image", images=(("x.png", b"not a png", "broken"),))
    # render_html always puts the verdict first: push it below the fold by hand, as a broken renderer would
    html_text = render_html("probe", "intro", [*filler, bad]).replace(
        "</body>", '<h2>Verdict</h2><p class="note">FAIL: late</p></body>')
    out = _probe(html_text, tmp_path)
    assert out["broken"] == ["broken"]
    assert out["verdict_bottom"] > out["viewport"]
    assert any("IMG" in e for e in out["errors"])


def _joint_and_coverage_sections():
    """The joint table from a stored contact-FE run (cases/laws, the unedited check-joints JSON) and a table
    with an explained missing value, rendered as the verify report renders them."""
    from femcheck.fe_device.joint_check import joint_table_rows, joint_table_section
    root = Path(__file__).resolve().parents[1]
    results = json.loads((root / "cases" / "laws" / "haptic_6psu_spherical_coarse.json").read_text())
    joints = joint_table_section(joint_table_rows(results))
    cov = Section("coverage", ({"element": "guideway", "min_detectable_pct": 2.5},
                               {"element": "actuation", "min_detectable_pct": None}), part="coverage",
                  explain={"min_detectable_pct": "no mutation is caught"})
    return joints, cov


def test_joint_table_shows_numbers_in_the_browser(tmp_path):
    """The joint table as the verify report writes it: numbers in every cell, missing values explained."""
    from femcheck.verify.render import verdict_section
    joints, cov = _joint_and_coverage_sections()
    out = _probe(render_html("probe", "intro", [joints, cov, verdict_section([], [], 1.0)]), tmp_path)
    assert out["cells"] >= 4 * 6 + 4 and out["bad_cells"] == [], out    # 4 components x 6 columns + coverage
    assert out["anchors_ok"] and out["errors"] == [], out


def test_browser_probe_sees_bare_format_codes_none_and_unexplained_gaps(tmp_path):
    """The cell check can fail: the joint table through a writer that does not apply its specs, a None and
    an unexplained gap are all caught."""
    import dataclasses
    joints, cov = _joint_and_coverage_sections()
    raw = dataclasses.replace(joints, rows=tuple({**r, "fe_compliance": ".4g", "error_pct": "+.1f"}
                                                 for r in joints.rows))
    gaps = Section("gaps", ({"a": "None", "b": None},))
    out = _probe(render_html("probe", "intro", [raw, gaps, dataclasses.replace(cov, explain={})]), tmp_path)
    assert sorted(set(out["bad_cells"])) == sorted({".4g", "+.1f", "None", "n/a"}), out
