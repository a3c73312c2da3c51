"""Stopping a sweep: Ctrl-C exits 130 and stops the workers, a killed parent leaves no
orphan worker, the stored state resumes to the table of an uninterrupted run, and --resume refuses a
different sweep."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pyarrow.parquet as pq
import pytest

import femcheck
from conftest import assert_same_tables
from femcheck.errors import FemcheckError
from femcheck.sweep.parameters import parse_params
from femcheck.sweep.run import run_sweep
from femcheck.sweep.store import SweepStore

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "haptic_6psu.toml"
PARAMS = ["guideway.width_radial_m=0.010:0.020", "geometry.proximal_link_length_m=0.170:0.190"]
N = 1000  # one sample per task: the workers are frozen after 3 stored tasks, so the signal lands midway


def _args(out, *extra):
    return [sys.executable, "-m", "femcheck", "sweep", str(CASE), *sum((["--param", p] for p in PARAMS), []),
            "--design", "lhs", "--samples", str(N), "--points", "P0,P3,P7", "--jobs", "2", "--chunk", "1",
            "--no-report", "--out", str(out), *extra]


def _default_sigint() -> None:
    """In the child before exec: Ctrl-C's default action. A shell's background job (pytest started with ``&``)
    inherits SIGINT ignored, and Python then installs no KeyboardInterrupt handler: the sweep would never see it."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start_and_wait(out):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg", "OPENBLAS_NUM_THREADS": "1"}
    proc = subprocess.Popen(_args(out), cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_default_sigint)
    store = SweepStore(out)
    deadline = time.monotonic() + 120
    while len(store.chunk_files()) < 3 and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    workers = [c.pid for c in psutil.Process(proc.pid).children(recursive=True)] if proc.poll() is None else []
    return proc, store, workers, env


def _signal(pids, sig) -> None:
    for p in pids:
        try:
            os.kill(p, sig)
        except ProcessLookupError:   # a worker that has already exited
            pass


def _gone(pids, timeout=15.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        alive = [p for p in pids if psutil.pid_exists(p) and psutil.Process(p).status() != psutil.STATUS_ZOMBIE]
        if not alive:
            return True
        time.sleep(0.1)
    return False


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    case = femcheck.load_case(CASE)
    return run_sweep(case, parse_params(case, PARAMS), tmp_path_factory.mktemp("ref"), design="lhs", samples=N,
                     points=("P0", "P3", "P7"), jobs=0)


@pytest.mark.parametrize("how", ["ctrl_c", "kill_parent"])
def test_stopped_sweep_leaves_no_worker_and_resumes_identically(tmp_path, uninterrupted, how):
    proc, store, workers, env = _start_and_wait(tmp_path / "run")
    assert proc.poll() is None and workers, "the sweep must still be running with its workers for this test to mean anything"
    # the workers are frozen before the parent gets its signal, so that the sweep cannot finish in between (on a warm
    # cache the remaining tasks take about a second); a frozen worker keeps the parent's SIGTERM (or the kernel's death
    # signal) pending and acts on it once thawed, after the parent has handled its own signal
    _signal(workers, signal.SIGSTOP)
    proc.send_signal(signal.SIGINT if how == "ctrl_c" else signal.SIGKILL)
    if how == "ctrl_c":   # the parent stores status "interrupted" after it has told its workers to stop
        deadline = time.monotonic() + 60
        while store.read_manifest().get("status") != "interrupted" and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
    else:
        proc.wait(timeout=60)
    _signal(workers, signal.SIGCONT)
    rc = proc.wait(timeout=60)
    out, err = proc.communicate()
    if how == "ctrl_c":
        assert rc == 130, err
        assert "interrupted" in out + err and "--resume" in " ".join((out + err).split())
        assert "Traceback" not in err
        assert store.read_manifest()["status"] == "interrupted"
    else:
        assert rc == -signal.SIGKILL
    # a worker must not outlive the parent (prctl death signal / parent watch: within a few seconds)
    assert _gone(workers), f"orphan workers left: {workers}"
    stored = len(store.chunk_files())
    assert 3 <= stored < N
    done = subprocess.run(_args(tmp_path / "run", "--resume"), cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    assert_same_tables(pq.read_table(store.results_path), uninterrupted.table)


def test_resume_with_other_parameters_is_refused_and_names_the_difference(tmp_path):
    case = femcheck.load_case(CASE)
    run_sweep(case, parse_params(case, PARAMS), tmp_path, design="lhs", samples=8, points=("P0",), jobs=0)
    before = (tmp_path / "manifest.json").read_text()
    other = parse_params(case, ["guideway.width_radial_m=0.010:0.030", PARAMS[1]])
    with pytest.raises(FemcheckError, match=r"different sweep: --param"):
        run_sweep(case, other, tmp_path, design="lhs", samples=8, points=("P0",), jobs=0, resume=True)
    assert (tmp_path / "manifest.json").read_text() == before  # the stored sweep is untouched
