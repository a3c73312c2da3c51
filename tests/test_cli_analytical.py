"""The analytical CLI commands, run in-process (typer CliRunner)."""
from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from femcheck.cli import get_app, main
from tests.conftest import REFERENCE_CASE, ROOT

runner = CliRunner()


def test_help_documents_every_command():
    out = runner.invoke(get_app(), ["--help"]).output
    for cmd in ("stiffness", "map", "verify"):
        assert cmd in out


def test_stiffness_json(case):
    res = runner.invoke(get_app(), ["stiffness", str(REFERENCE_CASE), "--point", "P0", "--wrench", "15,0,0,0,0,0", "--json", "-"])
    assert res.exit_code == 0, res.output
    obj = json.loads(res.output)
    K, d = np.array(obj["K"]), np.array(obj["deflection"])
    assert K.shape == (6, 6) and d.shape == (6,)
    assert d[0] * 1e3 == pytest.approx(0.2662, abs=5e-5)      # docs/conventions.md reference, 4 decimals
    assert sum(obj["contributions"].values()) == pytest.approx(1.0, abs=1e-12)
    assert np.allclose(K @ d, [15, 0, 0, 0, 0, 0], atol=1e-9)


def test_stiffness_released_override_and_table(case):
    res = runner.invoke(get_app(), ["stiffness", str(REFERENCE_CASE), "--joints", "released", "--point", "P3"])
    assert res.exit_code == 0, res.output
    assert "released" in res.output and "contributions" in res.output and "N/mm" in res.output


def test_bad_input_gives_one_clear_line(tmp_path, capsys):
    assert main(["stiffness", str(REFERENCE_CASE), "--pose", "0,0,0.6,0,0,0"]) == 2
    assert "unreachable by chain (leg)" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text(REFERENCE_CASE.read_text().replace("ball_radius_m = 0.0035", "ball_radius_m = 0"))
    assert main(["stiffness", str(bad)]) == 2
    assert "legs[0].joints[2].hertz_point.ball_radius_m" in capsys.readouterr().err


def test_map_writes_png(tmp_path):
    out = tmp_path / "map.png"
    res = runner.invoke(get_app(), ["map", str(REFERENCE_CASE), "--model", "detailed", "--z", "0.025",
                                    "--direction", "y", "--out", str(out), "--resolution", "21"])
    assert res.exit_code == 0, res.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_map_refuses_to_overwrite_the_case(tmp_path):
    case_copy = tmp_path / "c.toml"
    case_copy.write_text(REFERENCE_CASE.read_text())
    assert main(["map", str(case_copy), "--out", str(case_copy)]) == 2
    assert case_copy.read_text() == REFERENCE_CASE.read_text()


def test_verify_check_against_committed_baseline(tmp_path):
    """CI regression: the analytical deflections must not drift from reports/baseline/analytical.json."""
    res = runner.invoke(get_app(), ["verify", str(REFERENCE_CASE), "--level", "none", "--out", str(tmp_path), "--check",
                                    "--baseline", str(ROOT / "reports/baseline/analytical.json")])
    assert res.exit_code == 0, res.output
    lines = res.stdout.strip().splitlines()
    assert lines[0].startswith("PASS: 1 check passed") and lines[-1] == lines[0]   # the verdict opens and closes
    verdict = json.loads((tmp_path / "verdict.json").read_text())
    assert verdict["checks"] == [{"name": "analytical drift", "kind": "drift", "status": "pass",
                                  "detail": verdict["checks"][0]["detail"]}] and "none drifted" in verdict["checks"][0]["detail"]
    for name in ("report.html", "manifest.json", "simplified_vs_detailed_rigid.csv", "contributions.png"):
        assert (tmp_path / name).is_file()
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert manifest["case_sha256"] and manifest["packages"]["numpy"]


def test_verify_check_detects_drift(tmp_path):
    base = json.loads((ROOT / "reports/baseline/analytical.json").read_text())
    key = "analytical/detailed/rigid/P0/+x/deflection_m"
    base[key] *= 1.01
    drifted = tmp_path / "base.json"
    drifted.write_text(json.dumps(base))
    res = runner.invoke(get_app(), ["verify", str(REFERENCE_CASE), "--level", "none", "--points", "P0", "--out", str(tmp_path / "run"),
                                    "--check", "--baseline", str(drifted)])
    assert res.exit_code == 1
    assert key in res.output and "drift" in res.output
