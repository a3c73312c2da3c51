"""The verify report in a real headless browser (issue 17 item 5): every image loads, the verdict is visible
without scrolling, no console error. Skipped with a reason when no Chromium is installed
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

import pytest

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
  var out = {images: imgs.length,
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
    run = run_verify(case, tmp_path / "run", points=("P0", "P7"))
    out = _probe((tmp_path / "run" / "report.html").read_text(encoding="utf-8"), tmp_path)
    assert out["images"] >= 4 and out["broken"] == [], out           # contributions + 3 deflection plots, all decoded
    assert out["verdict_bottom"] is not None and out["verdict_bottom"] <= out["viewport"], out  # above the fold
    assert out["verdict_text"].startswith("PASS"), out
    assert out["errors"] == [], out
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
