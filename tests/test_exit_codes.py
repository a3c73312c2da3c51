"""Exit codes of the real console script: 0 when everything holds, 1 for a failed check,
2 for bad input. Run in a subprocess so that the path the user takes (console script -> main -> sys.exit)
is the one under test; in-process CliRunner calls would not see a lost return code."""
from __future__ import annotations

import json
import re
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "haptic_6psu.toml"
BASELINE = ROOT / "reports" / "baseline" / "analytical.json"


def _run(*args, cwd=ROOT):
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "femcheck", *map(str, args)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)


def _scaled(obj, factor):
    if isinstance(obj, dict):
        return {k: _scaled(v, factor) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_scaled(v, factor) for v in obj]
    return obj * factor if isinstance(obj, float) else obj


@pytest.fixture(scope="module")
def drifted_baseline(tmp_path_factory):
    path = tmp_path_factory.mktemp("baseline") / "analytical_x1.5.json"
    path.write_text(json.dumps(_scaled(json.loads(BASELINE.read_text()), 1.5)))
    return path


def test_verify_check_exits_1_on_drift(drifted_baseline, tmp_path):
    r = _run("verify", CASE, "--level", "none", "--check", "--baseline", drifted_baseline, "--out", tmp_path / "run")
    assert r.returncode == 1, r.stdout[-2000:] + r.stderr[-2000:]
    assert "drift" in r.stdout
    assert "Traceback" not in r.stderr


def test_verify_check_exits_0_without_drift(tmp_path):
    r = _run("verify", CASE, "--level", "none", "--check", "--baseline", BASELINE, "--out", tmp_path / "run")
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]


def test_bad_case_exits_2_with_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(CASE.read_text().replace("outer_diameter_m = ", "outer_diameter_m = -", 1))
    r = _run("stiffness", bad)
    assert r.returncode == 2
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "outer_diameter_m" in lines[0] and "Traceback" not in r.stderr


def test_version_and_quiet(tmp_path):
    r = _run("--version")
    assert r.returncode == 0 and r.stdout.startswith("femcheck ")


def test_progress_off_a_terminal_is_plain_timestamped_lines(tmp_path):
    """Off a terminal (a pipe here), progress comes as plain lines with stage, count and time: no ANSI codes."""
    r = _run("sweep", CASE, "--param", "guideway.width_radial_m=0.010:0.020", "--samples", "32", "--jobs", "0",
             "--no-report", "--out", tmp_path / "s")
    assert r.returncode == 0, r.stderr
    lines = [ln for ln in r.stdout.splitlines() if "[sweep tasks]" in ln]
    assert lines and re.match(r"\d\d:\d\d:\d\d \[sweep tasks\] (\d+)/\1 \(100 %\) elapsed .* \(done\)$", lines[-1]), lines
    assert "\x1b[" not in r.stdout + r.stderr
    q = _run("-q", "sweep", CASE, "--param", "guideway.width_radial_m=0.010:0.020", "--samples", "32", "--jobs", "0",
             "--no-report", "--out", tmp_path / "q")
    assert q.returncode == 0 and "[sweep tasks]" not in q.stdout


def test_heartbeat_prints_during_a_long_step(capsys):
    """A single long step still shows life every interval (the heartbeat thread)."""
    import time

    from rich.console import Console

    from femcheck.cli._progress import StageProgress

    with StageProgress("long", 3, Console(file=sys.stdout), tty=False, interval_s=0.2) as bar:
        time.sleep(0.75)
        bar.advance(1, "first")
    out = capsys.readouterr().out.splitlines()
    assert sum("[long] 0/3" in ln for ln in out) >= 3   # started + >= 2 heartbeats while the step ran
    assert "ETA" in out[-2] or "(done)" in out[-1]
