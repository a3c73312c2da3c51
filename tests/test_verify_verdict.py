"""`femcheck verify` verdicts through the real CLI, analytical level (seconds): a run that evaluates no check is
not a PASS, a baseline without the configuration's keys is bad input (exit 2) and never drift, and the terminal
opens and closes with the verdict. The threshold side (a wrong law exits 1 with or without --check) is
tests/test_verify_mutations.py."""
from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from conftest import REFERENCE_CASE, ROOT
from femcheck.cli import get_app, main

runner = CliRunner()
BASELINE = ROOT / "reports" / "baseline" / "analytical.json"


def _lines(output: str) -> list[str]:
    return [ln for ln in output.strip().splitlines() if ln.strip()]


def test_analytical_only_without_check_is_not_a_pass(tmp_path):
    """Nothing evaluated (no FE level, no --check): FAIL, exit 1, first and last line say so; every check in
    verdict.json has kind, status and the reason it was skipped."""
    res = runner.invoke(get_app(), ["verify", str(REFERENCE_CASE), "--level", "none", "--points", "P0",
                                    "--out", str(tmp_path)])
    assert res.exit_code == 1, res.output
    lines = _lines(res.stdout)
    assert lines[0].startswith("FAIL: no check was evaluated") and lines[-1] == lines[0]
    v = json.loads((tmp_path / "verdict.json").read_text())
    assert v["passed"] is False and v["verdict"] == "FAIL" and v["evaluated"] == 0
    assert v["checks"] and all(c["status"] == "skipped" and c["kind"] in ("threshold", "drift", "idealization",
                                                                          "convergence") and c["reason"]
                               for c in v["checks"])
    # tables that no check reads are labelled where they are printed
    assert "simplified vs detailed analytical model, rigid joints (relative error %) — informational, not a check" \
        in " ".join(res.output.split())


@pytest.fixture()
def baseline_without_p0(tmp_path):
    base = json.loads(BASELINE.read_text())
    gone = [k for k in base if "/P0/" in k]
    for k in gone:
        del base[k]
    path = tmp_path / "analytical_without_P0.json"
    path.write_text(json.dumps(base))
    return path, gone


def test_missing_analytical_keys_are_a_named_error_not_drift(baseline_without_p0, tmp_path):
    """A baseline lacking P0: exit 2 (bad input), one line naming the file, the keys and --update-baseline; no
    report is left claiming a verdict."""
    path, gone = baseline_without_p0
    rc = main(["verify", str(REFERENCE_CASE), "--level", "none", "--points", "P0,P5", "--check", "--baseline", str(path),
               "--out", str(tmp_path / "run")])
    assert rc == 2
    assert not (tmp_path / "run" / "verdict.json").exists()


def test_missing_baseline_message_names_keys_and_update_baseline(baseline_without_p0, tmp_path, capsys):
    path, gone = baseline_without_p0
    main(["verify", str(REFERENCE_CASE), "--level", "none", "--points", "P0,P5", "--check", "--baseline", str(path),
          "--out", str(tmp_path / "run")])
    err = " ".join(capsys.readouterr().err.split())
    assert f"lacks {len(gone)} key(s)" in err and "analytical/detailed/rigid/*/deflection_m at P0" in err
    assert "--update-baseline" in err and str(path) in err
    # P5 is in the file: it is not named as missing
    assert "P5" not in err.split("lacks")[1]


def test_fe_baseline_without_joint_fe_keys_fails_before_the_fe_runs(tmp_path, capsys):
    """The detailed FE with the joints' contact-FE laws has its own keys (+joint_fe); a baseline holding only the
    closed-form ones is a named error found before any FE solve (exit 2 within seconds), not a silent skip."""
    only_closed_form = tmp_path / "fe_closed_form_only.json"
    only_closed_form.write_text(json.dumps({k: v for k, v in json.loads((ROOT / "reports/baseline/fe_coarse.json")
                                                                        .read_text()).items() if "+joint_fe" not in k}))
    import time
    t0 = time.perf_counter()
    rc = main(["verify", str(REFERENCE_CASE), "--level", "detailed", "--mesh", "coarse", "--points", "P0", "--check",
               "--fe-baseline", str(only_closed_form), "--out", str(tmp_path / "run")])
    seconds = time.perf_counter() - t0
    err = " ".join(capsys.readouterr().err.split())
    assert rc == 2, err
    assert "fe/coarse/solid/detailed/rigid+joint_fe/*/deflection_m at P0" in err and "--update-baseline" in err
    assert "contact_fe_slip+joint_fe" in err
    assert seconds < 60, seconds   # no FE solve ran (the contact FE alone takes minutes)
