"""Sweep execution: local pool vs Dask LocalCluster vs in-process, interruption and --resume."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import femcheck
from conftest import assert_same_tables
from femcheck.errors import CaseError, FemcheckError
from femcheck.sweep.evaluate_analytical import run_analytical_task
from femcheck.sweep.executor import SweepInterrupted
from femcheck.sweep.parameters import parse_params
from femcheck.sweep.run import run_sweep
from femcheck.sweep.store import SweepStore

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "haptic_6psu.toml"
#: one array-type and one variant-type key, so both evaluation paths run in every backend
PARAMS = ["guideway.width_radial_m=0.010:0.020", "geometry.proximal_link_length_m=0.170:0.190"]


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case(CASE)


@pytest.fixture(scope="module")
def ranges(case):
    return parse_params(case, PARAMS)


def _sweep(case, ranges, out, **kw):
    kw.setdefault("design", "lhs")
    kw.setdefault("samples", 24)
    kw.setdefault("chunk_samples", 4)
    kw.setdefault("points", ("P0", "P3", "P7"))
    return run_sweep(case, ranges, out, **kw)


_assert_same = assert_same_tables


@pytest.fixture(scope="module")
def reference(case, ranges, tmp_path_factory):
    """The uninterrupted sweep, in this process."""
    return _sweep(case, ranges, tmp_path_factory.mktemp("ref"), jobs=0)


def test_reference_sweep_is_complete(reference):
    t = reference.table
    assert t.num_rows == 24 * 3
    assert reference.manifest["status"] == "complete"
    assert all(t.column("ok").to_pylist())
    assert len(SweepStore(reference.store.root).chunk_files()) == 6  # 24 samples / 4 per task


@pytest.mark.parametrize("start", ["fork", "spawn"])
def test_local_pool_matches_in_process(case, ranges, reference, tmp_path, monkeypatch, start):
    monkeypatch.setenv("FEMCHECK_POOL_START", start)
    pooled = _sweep(case, ranges, tmp_path, jobs=2)
    assert pooled.manifest["timing"]["backend"] == "process-pool"
    _assert_same(pooled.table, reference.table)


@pytest.fixture(scope="module")
def dask_cluster():
    """A real Dask cluster on loopback: 2 worker processes, 1 thread each; closed after the module."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None, silence_logs=40) as cluster:
        yield cluster


def test_dask_local_cluster_matches_local(case, ranges, reference, tmp_path, dask_cluster):
    out = _sweep(case, ranges, tmp_path, scheduler=dask_cluster.scheduler_address)
    assert out.manifest["timing"]["backend"] == "dask"
    assert out.manifest["timing"]["workers"] == 2
    _assert_same(out.table, reference.table)


def test_scheduler_from_environment(case, ranges, reference, tmp_path, monkeypatch, dask_cluster):
    monkeypatch.setenv("FEMCHECK_SCHEDULER", dask_cluster.scheduler_address)
    out = _sweep(case, ranges, tmp_path, jobs=2)
    assert out.manifest["timing"]["backend"] == "dask"
    _assert_same(out.table, reference.table)


def test_dask_task_failure_keeps_finished_chunks(case, ranges, reference, tmp_path, dask_cluster):
    with pytest.raises(SweepInterrupted, match="failed on the cluster"):
        _sweep(case, ranges, tmp_path, scheduler=dask_cluster.scheduler_address, task_fn=fail_on_third_chunk)
    done = len(SweepStore(tmp_path).chunk_files())
    assert done <= 5  # the failing chunk is never stored
    out = _sweep(case, ranges, tmp_path, scheduler=dask_cluster.scheduler_address, resume=True)
    assert out.manifest["resumed_with_finished_samples"] == 4 * done
    _assert_same(out.table, reference.table)


def fail_on_third_chunk(task):
    """Task that raises on the chunk starting at sample 8 (a failing FE sample, say)."""
    if int(task.sample_ids[0]) == 8:
        raise RuntimeError("simulated task failure")
    return run_analytical_task(task)


class _FailAfter:
    """Task function that runs ``k`` tasks, then raises (simulates Ctrl-C or a failure midway)."""

    def __init__(self, k, exc):
        self.k, self.exc, self.calls = k, exc, 0

    def __call__(self, task):
        self.calls += 1
        if self.calls > self.k:
            raise self.exc
        return run_analytical_task(task)


def test_interrupted_sweep_resumes_to_identical_results(case, ranges, reference, tmp_path):
    with pytest.raises(SweepInterrupted, match="2 of 6 tasks finished"):
        _sweep(case, ranges, tmp_path, jobs=0, task_fn=_FailAfter(2, RuntimeError("simulated failure")))
    store = SweepStore(tmp_path)
    assert len(store.chunk_files()) == 2
    assert store.read_manifest()["status"] == "interrupted"
    with pytest.raises(FemcheckError, match="--resume"):
        _sweep(case, ranges, tmp_path, jobs=0)  # refuses to mix without --resume
    counter = _FailAfter(10**6, None)
    out = _sweep(case, ranges, tmp_path, jobs=0, resume=True, task_fn=counter)
    assert counter.calls == 4  # only the unfinished tasks ran
    assert out.manifest["resumed_with_finished_samples"] == 8
    _assert_same(out.table, reference.table)


def test_ctrl_c_keeps_finished_chunks(case, ranges, reference, tmp_path):
    with pytest.raises(KeyboardInterrupt):
        _sweep(case, ranges, tmp_path, jobs=0, task_fn=_FailAfter(3, KeyboardInterrupt()))
    assert len(SweepStore(tmp_path).chunk_files()) == 3
    out = _sweep(case, ranges, tmp_path, jobs=0, resume=True)
    _assert_same(out.table, reference.table)


def crash_on_third_chunk(task):
    """Pool task that kills its worker process on the chunk starting at sample 8 (a worker crash)."""
    if int(task.sample_ids[0]) == 8:
        os._exit(3)
    return run_analytical_task(task)


def test_worker_crash_loses_no_finished_chunk(case, ranges, reference, tmp_path):
    with pytest.raises(SweepInterrupted, match="worker process died"):
        _sweep(case, ranges, tmp_path, jobs=1, task_fn=crash_on_third_chunk)
    done = len(SweepStore(tmp_path).chunk_files())
    assert done == 2  # one worker runs the chunks in order: samples 0-3 and 4-7 were stored before the crash
    out = _sweep(case, ranges, tmp_path, jobs=2, resume=True)
    assert out.manifest["resumed_with_finished_samples"] == 8
    _assert_same(out.table, reference.table)


def test_cli_killed_by_signal_resumes(case, ranges, tmp_path):
    """A real `femcheck sweep` process killed with SIGKILL midway; --resume finishes it identically."""
    n = 800  # one sample per task (--chunk 1): several seconds of work, so the kill lands midway under load too
    args = [sys.executable, "-m", "femcheck", "sweep", str(CASE), *sum((["--param", p] for p in PARAMS), []),
            "--design", "lhs", "--samples", str(n), "--points", "P0,P3,P7", "--jobs", "0", "--chunk", "1",
            "--no-report", "--out", str(tmp_path / "killed")]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    proc = subprocess.Popen(args, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    store = SweepStore(tmp_path / "killed")
    deadline = time.monotonic() + 90
    while len(store.chunk_files()) < 3 and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    killed_with = len(store.chunk_files())
    assert 3 <= killed_with < n, "the process must be killed midway for this test to mean anything"
    done = subprocess.run(args + ["--resume"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert f"{killed_with} samples reused" in " ".join(done.stdout.split())
    import pyarrow.parquet as pq
    uninterrupted = _sweep(case, ranges, tmp_path / "ref", jobs=0, samples=n, chunk_samples=None)
    _assert_same(pq.read_table(store.results_path), uninterrupted.table)


def test_fe_sweep_bad_mesh_level_is_a_clear_error_before_any_work(case, ranges, tmp_path):
    with pytest.raises(CaseError, match="--mesh"):
        run_sweep(case, ranges, tmp_path, model="fe", mesh="medium")
    assert not any(tmp_path.iterdir())


def test_longer_sobol_sequence_reuses_stored_samples(case, ranges, tmp_path):
    """A resumed Sobol' sweep with twice the base samples reuses the A/B rows it shares with the shorter
    one (their sample ids change); the result equals a fresh sweep of the longer design."""
    short = _sweep(case, ranges, tmp_path / "s", design="sobol", samples=8, jobs=0)
    assert short.design.m == 8 * 4
    longer = _sweep(case, ranges, tmp_path / "s", design="sobol", samples=16, jobs=0, resume=True)
    assert longer.manifest["resumed_with_finished_samples"] > 0
    fresh = _sweep(case, ranges, tmp_path / "f", design="sobol", samples=16, jobs=0)
    _assert_same(longer.table, fresh.table)
