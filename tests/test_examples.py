"""The narrated scripts in examples/ run and pass their own checks (as scikit-fem pins its docs examples),
and the README's Python API snippet runs as printed."""
import os
import re
import subprocess
import sys

import pytest

from conftest import ROOT

EXAMPLES = sorted((ROOT / "examples").glob("*.py"))


def test_there_are_examples():
    assert {p.stem for p in EXAMPLES} >= {"python_api", "serial_deflection", "diagnosis", "urdf_workflow"}
    assert (ROOT / "examples" / "urdf" / "arm3.urdf").is_file()   # the URDF the workflow example imports


@pytest.mark.parametrize("script", EXAMPLES, ids=lambda p: p.stem)
def test_example_runs_and_passes_its_checks(script):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg", "OPENBLAS_NUM_THREADS": "1"}
    res = subprocess.run([sys.executable, str(script)], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    # every example ends in its own assertions and says so; a script that stops early cannot print this
    assert f"{script.stem}: all checks passed" in res.stdout


def test_readme_python_api_snippet_runs(monkeypatch):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Python API", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(ROOT)
    scope: dict = {}
    exec(compile(code, "README.md (Python API)", "exec"), scope)
    # the snippet's results have the shapes the README states
    assert scope["t"].shape == (9, 6) and scope["K"].shape == (9, 6, 6)
    assert scope["variant"].guideway.width_radial_m == 0.016
