"""verify/ split: the verdict leads the report, verdict.json / junit.xml list every check, one pivot for the
error tables, worst errors only from checked comparisons."""
import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from femcheck.verify.check import Check, threshold_checks
from femcheck.verify.compute import pivot_errors, worst_errors
from femcheck.verify.render import Section, junit_xml, render_html, render_markdown, verdict_json, verdict_section

CHECKS = [Check("analytical drift", "drift", "pass", "no drift"),
          Check("threshold detailed/rigid +x", "threshold", "fail", "12 % > 10 %"),
          Check("FE drift", "drift", "skipped", "drift against the baseline", reason="no --check")]


def test_verdict_section_leads_markdown_and_html_wherever_it_is_appended():
    sections = [Section("Errors", ({"point": "P0", "+x error %": 1.0},)), verdict_section(CHECKS, [], 3.2)]
    md = render_markdown("t", "intro", sections)
    assert md.index("## Verdict") < md.index("## Errors")
    assert "FAIL: 1 of 2 checks failed (threshold detailed/rigid +x); worst error: none (no FE level run). Run time 3.2 s." in md
    html = render_html("t", "intro", sections)
    assert html.index('<h2 id="verdict">Verdict</h2>') < html.index(">Errors</h2>")


def test_verdict_json_and_junit_have_one_entry_per_check():
    v = json.loads(verdict_json(CHECKS, [], 1.0))
    assert v["passed"] is False and v["verdict"] == "FAIL" and v["failed_checks"] == ["threshold detailed/rigid +x"]
    assert [c["status"] for c in v["checks"]] == ["pass", "fail", "skipped"]
    assert [c["kind"] for c in v["checks"]] == ["drift", "threshold", "drift"]
    # only a skipped check carries a reason
    assert [c.get("reason") for c in v["checks"]] == [None, None, "no --check"]
    suite = ET.fromstring(junit_xml(CHECKS, 1.0))
    assert suite.get("tests") == "3" and suite.get("failures") == "1" and suite.get("skipped") == "1"
    cases = suite.findall("testcase")
    assert [c.get("name") for c in cases] == [c.name for c in CHECKS]
    assert cases[1].find("failure").get("message") == "12 % > 10 %" and cases[0].find("failure") is None
    assert cases[2].find("skipped").get("message") == "no --check"
    assert json.loads(verdict_json(CHECKS[:1], [], 1.0))["passed"] is True


def test_a_run_in_which_no_check_was_evaluated_is_not_a_pass():
    """Only skipped checks (analytical only, no --check): FAIL in verdict.json, the report and JUnit."""
    skipped = [CHECKS[2]]
    v = json.loads(verdict_json(skipped, [], 1.0))
    assert v["passed"] is False and v["verdict"] == "FAIL" and v["evaluated"] == 0
    assert v["summary"].startswith("FAIL: no check was evaluated")
    assert verdict_section(skipped, [], 1.0).note.startswith("FAIL: no check was evaluated")
    suite = ET.fromstring(junit_xml(skipped, 1.0))
    assert suite.get("failures") == "1"   # a CI reading only JUnit sees red too
    assert json.loads(verdict_json([], [], 1.0))["passed"] is False


def test_check_kind_status_and_reason_are_validated():
    with pytest.raises(ValueError, match="kind"):
        Check("x", "regression", "pass")
    with pytest.raises(ValueError, match="status"):
        Check("x", "drift", "ok")
    with pytest.raises(ValueError, match="reason"):
        Check("x", "drift", "skipped")                   # a skipped check must say why
    with pytest.raises(ValueError, match="reason"):
        Check("x", "drift", "pass", reason="no --check")  # and only a skipped one


def test_verdict_line_names_failed_checks_and_worst_error():
    from femcheck.verify.check import verdict
    worst = [{"table": "detailed/released", "direction": "+x", "mean_error_pct": 187.3}]
    v = verdict(CHECKS, worst)
    assert v.line() == ("FAIL: 1 of 2 checks failed (threshold detailed/rigid +x); worst error: detailed/released +x "
                        "mean 187.30 % (threshold 10 %)")
    ok = verdict(CHECKS[:1], [{"table": "simplified/rigid", "direction": "+z", "mean_error_pct": 0.2}])
    assert ok.passed and ok.line() == ("PASS: 1 check passed (0 skipped); worst error: simplified/rigid +z mean 0.20 % "
                                       "(threshold 5 %)")


def test_pivot_gives_rows_then_average_and_max():
    rng = np.random.default_rng(3)
    err = {(p, d): float(rng.uniform(0, 20)) for p in ("P0", "P1", "P2") for d in ("+x", "+z")}
    rows = pivot_errors(err, ("P0", "P1", "P2"), ("+x", "+z"))
    assert [r["point"] for r in rows] == ["P0", "P1", "P2", "average", "max"]
    for d in ("+x", "+z"):
        col = [err[(p, d)] for p in ("P0", "P1", "P2")]
        assert rows[3][f"{d} error %"] == pytest.approx(np.mean(col), rel=1e-15)  # same numbers, same mean
        assert rows[4][f"{d} error %"] == max(col)


def test_thresholds_and_worst_errors_skip_the_idealization_the_contact_fe_does_not_follow():
    avg = lambda v: [{"point": "P0", "+x error %": v}, {"point": "average", "+x error %": v}]
    tabs = {("detailed", "rigid", "contact"): avg(60.0), ("detailed", "released", "contact"): avg(0.8),
            ("simplified", "rigid", "rigid"): avg(6.0)}
    checks = {c.name: c.status for c in threshold_checks(tabs)}
    assert checks == {"contact FE follows the expected idealization": "pass",
                      "threshold detailed/released vs contact FE +x": "pass", "threshold simplified/rigid +x": "fail"}
    assert [w["table"] for w in worst_errors(tabs)] == ["simplified/rigid", "detailed/released/contact"]


def test_contact_fe_following_another_idealization_than_expected_fails():
    """The expected idealization is stated before the run: a contact FE that ends up closer to rigid fails,
    and its thresholds are checked against the expected (released) one, not the one it happens to follow."""
    avg = lambda v: [{"point": "P0", "+x error %": v}, {"point": "average", "+x error %": v}]
    tabs = {("detailed", "rigid", "contact"): avg(3.0), ("detailed", "released", "contact"): avg(40.0)}
    checks = {c.name: c.status for c in threshold_checks(tabs)}
    assert checks["contact FE follows the expected idealization"] == "fail"
    assert checks["threshold detailed/released vs contact FE +x"] == "fail"
    assert "threshold detailed/rigid vs contact FE +x" not in checks


def test_the_verdict_leads_even_when_other_sections_ask_to_be_first():
    from femcheck.verify.render import Section, ordered, verdict_section
    secs = [Section("a"), Section("coverage", first=True), verdict_section([], [], 1.0), Section("b")]
    assert [s.title for s in ordered(secs)] == ["Verdict", "coverage", "a", "b"]
    # a verdict not marked first still leads, once
    assert [s.title for s in ordered([Section("a"), Section("Verdict")])] == ["Verdict", "a"]


def test_sections_follow_the_readers_order_with_contents_and_raw_deflections_folded_last():
    """Verdict, contents, then coverage, errors, joints, contact diagnosis, convergence, supporting, raw;
    whatever order the run appends them in."""
    from femcheck.verify.render import Section, render_html, render_markdown, verdict_section
    secs = [Section("raw", ({"point": "P0", "dx_mm": 0.1},), part="raw", collapsed=True, informational=True),
            Section("plot"), Section("conv", part="convergence"), Section("diag", part="contact_diagnosis"),
            Section("joints", part="joints"), Section("err", part="errors"), Section("cov", part="coverage"),
            verdict_section([], [], 1.0)]
    want = ["Verdict", "cov", "err", "joints", "diag", "conv", "plot", "raw"]
    for text, head in ((render_html("t", "i", secs), lambda t: f">{t}</h2>"),
                       (render_markdown("t", "i", secs), lambda t: f"## {t}\n")):
        pos = [text.index(head(t)) for t in want]
        assert pos == sorted(pos), (want, pos)
        contents = text.index("Contents")
        assert pos[0] < contents < pos[1]                       # the verdict first, the contents right after it
        for anchor in ("#verdict", "#s1", "#s7"):
            assert anchor in text[contents:pos[1]]              # every section is linked from the contents
        raw = text[pos[-1]:]
        assert "<details>" in raw and "Informational" in raw    # folded and labelled


def test_table_writer_takes_bare_and_braced_format_specs_and_never_prints_none_or_nan():
    from femcheck.report import tables
    rows = [{"a": 0.000123456, "b": float("nan"), "c": None, "d": True}]
    _cols, body = tables.cells(rows, {"a": ".4g", "b": "{:.2f}", "d": "{:.1f}"})
    assert body == [["0.0001235", "n/a", "n/a", "True"]]     # the spec applies; bools are not numbers here
    html = tables.to_html(rows, {"a": "{:.4g}"}, explain={"c": "no such law"})
    assert 'title="no such law">n/a' in html and "n/a in c: no such law" in html


def test_vtu_of_the_first_point_by_default_every_point_on_request():
    """--vtu first (default) writes one deformed-model VTU (about 40 MB at the default mesh), all one per point,
    none nothing; anything else is refused."""
    import pytest

    from femcheck.verify.run import vtu_points
    pts = ("P0", "P1", "P2")
    assert vtu_points("first", pts) == ("P0",) and vtu_points(True, pts) == ("P0",)
    assert vtu_points("all", pts) == pts
    assert vtu_points("none", pts) == () and vtu_points(False, pts) == ()
    with pytest.raises(ValueError, match="expected one of first, all, none"):
        vtu_points("some", pts)
