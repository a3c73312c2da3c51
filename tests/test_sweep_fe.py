"""FE samples in parameter sweeps (``femcheck sweep --model fe``): the FE task, back ends, resume, CLI.

One coarse FE sample at one point (P0) costs about 15-20 s on the 2-core development machine (the link
super-element, ~88,000 DOFs, dominates), so the tests that solve FE samples are marked slow; the fast
ones check the task plumbing (keys, chunking, failures, option errors) without an FE solve.
"""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import femcheck
from conftest import assert_same_tables
from femcheck.cli import get_app
from femcheck.errors import CaseError
from femcheck.sweep.evaluate_analytical import result_columns
from femcheck.sweep.evaluate_fe import FETask, run_fe_task
from femcheck.sweep.parameters import parse_params
from femcheck.sweep.run import run_sweep
from femcheck.sweep.store import SweepStore

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "haptic_6psu.toml"
#: two grid levels of the link tube's outer diameter (inner 5 mm): the nominal 6 mm and 6.5 mm
PARAM = "proximal_link.outer_diameter_m=0.0060:0.0065:2"
POINTS = ("P0",)

pytestmark = pytest.mark.usefixtures("isolated_mesh_cache")


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case(CASE)


@pytest.fixture(scope="module")
def ranges(case):
    return parse_params(case, [PARAM])


def _fe_sweep(case, ranges, out, **kw):
    kw.setdefault("jobs", 0)
    return run_sweep(case, ranges, out, design="grid", model="fe", points=POINTS, mesh="coarse",
                     fe_level="detailed", **kw)


_assert_same = assert_same_tables


# -- fast: plumbing without an FE solve -------------------------------------------------------------

def stub_fe_task(task: FETask) -> dict:
    """Stand-in for :func:`run_fe_task` with its column layout (constant numbers, no FE solve)."""
    n = task.n_samples * len(task.points)
    out = {"sample_id": np.repeat(task.sample_ids.astype(np.int64), len(task.points)),
           "sample_key": np.repeat(np.asarray(task.sample_keys, dtype=object), len(task.points)),
           "point": np.tile(np.asarray(task.points, dtype=object), task.n_samples)}
    for j, key in enumerate(task.keys):
        out[f"p:{key}"] = np.repeat(task.values[:, j], len(task.points))
    out.update({c: np.ones(n) for c in result_columns(task.keys, task.case.loads.directions)[len(task.keys):]})
    out["ok"] = np.ones(n, dtype=bool)
    out["failure"] = np.full(n, "", dtype=object)
    return out


def _keys(outcome) -> list[str]:
    return outcome.table.column("sample_key").to_pylist()


def test_fe_sweep_one_sample_per_task_and_own_keys(case, ranges, tmp_path):
    fe = _fe_sweep(case, ranges, tmp_path / "coarse", task_fn=stub_fe_task)
    assert fe.manifest["status"] == "complete"
    assert fe.manifest["timing"]["tasks"] == 2  # one FE sample per task
    assert len(SweepStore(fe.store.root).chunk_files()) == 2
    assert fe.manifest["options"]["mesh"] == "coarse" and fe.manifest["options"]["fe_level"] == "detailed"
    fine = run_sweep(case, ranges, tmp_path / "fine", design="grid", model="fe", points=POINTS, mesh="fine",
                     jobs=0, task_fn=stub_fe_task)
    simplified = run_sweep(case, ranges, tmp_path / "simpl", design="grid", model="fe", points=POINTS,
                           fe_level="simplified", jobs=0, task_fn=stub_fe_task)
    analytical = run_sweep(case, ranges, tmp_path / "an", design="grid", model="detailed", points=POINTS, jobs=0)
    assert "mesh" not in analytical.manifest["options"]  # analytical keys are unchanged by the FE options
    key_sets = [set(_keys(o)) for o in (fe, fine, simplified, analytical)]
    for i in range(len(key_sets)):
        for j in range(i):
            assert not key_sets[i] & key_sets[j], "an FE sample must never resume from another model or mesh"


def test_invalid_variant_is_a_failed_sample_not_a_failed_sweep(case):
    # outer diameter 4 mm < inner 5 mm: the case variant is invalid; the sample fails before any FE solve
    task = FETask(case=case, keys=("proximal_link.outer_diameter_m",), kinds=("array",),
                  values=np.array([[0.004]]), sample_ids=np.array([7]), sample_keys=("k7",), level="detailed",
                  joints="rigid", points=("P0", "P3"), mesh="coarse")
    rows = run_fe_task(task)
    assert list(rows["sample_id"]) == [7, 7] and list(rows["point"]) == ["P0", "P3"]
    assert not rows["ok"].any()
    assert all("invalid case variant" in f and "outer_diameter_m" in f for f in rows["failure"])
    assert np.isnan(rows["k_x_N_per_m"]).all() and np.isnan(rows["mass_kg"]).all()
    assert set(result_columns(task.keys, case.loads.directions)) <= set(rows)


@pytest.mark.parametrize("option, value", [("mesh", "medium"), ("fe_level", "exact")])
def test_run_sweep_bad_fe_option_names_it(case, ranges, tmp_path, option, value):
    flag = "--" + option.replace("_", "-")
    with pytest.raises(CaseError, match=flag):
        run_sweep(case, ranges, tmp_path, model="fe", points=POINTS, jobs=0, **{option: value})
    assert not SweepStore(tmp_path).has_results()


def test_cli_bad_mesh_value_names_the_option(tmp_path):
    args = ["sweep", str(CASE), "--param", PARAM, "--model", "fe", "--points", "P0", "--jobs", "0",
            "--no-report", "--out", str(tmp_path / "out")]
    res = CliRunner().invoke(get_app(), args + ["--mesh", "medium"])
    assert res.exit_code == 2
    assert "--mesh" in res.output and "medium" in res.output
    res = CliRunner().invoke(get_app(), args + ["--fe-level", "exact"])
    assert res.exit_code == 2 and "--fe-level" in res.output
    res = CliRunner().invoke(get_app(), ["sweep", str(CASE), "--param", PARAM, "--model", "detailed",
                                         "--mesh", "fine", "--out", str(tmp_path / "out2")])
    assert res.exit_code == 2 and "--mesh applies to --model fe only" in res.output
    assert not (tmp_path / "out").exists() and not (tmp_path / "out2").exists()


def test_cli_fe_sweep_end_to_end_with_stub_task(tmp_path, monkeypatch):
    """The CLI pipeline of --model fe (progress, analysis, analytical local elasticities, HTML summary),
    with the FE task replaced by the stub so that no FE is solved."""
    import femcheck.sweep.run as run_mod
    monkeypatch.setitem(run_mod.TASK_FUNCTIONS, "fe", stub_fe_task)
    out = tmp_path / "out"
    res = CliRunner().invoke(get_app(), ["sweep", str(CASE), "--param", PARAM, "--design", "grid", "--model", "fe",
                                         "--mesh", "default", "--points", "P0", "--jobs", "0", "--out", str(out)])
    assert res.exit_code == 0, res.output
    text = " ".join(res.output.split())
    assert "FE level detailed, mesh default" in text and "analytical detailed model" in text
    man = SweepStore(out).read_manifest()
    assert man["options"]["mesh"] == "default" and man["timing"]["tasks"] == 2
    assert (out / "summary.html").is_file() and (out / "results.parquet").is_file()


# -- slow: real FE samples ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def reference(case, ranges, tmp_path_factory):
    """The 2-sample FE sweep at P0 (coarse mesh, detailed FE level), in this process."""
    return _fe_sweep(case, ranges, tmp_path_factory.mktemp("fe_ref"))


@pytest.mark.slow
def test_fe_sweep_equals_direct_fe_and_link_stiffens(case, reference):
    from femcheck.verify.fe import run_fe
    t = reference.table
    assert t.num_rows == 2 and all(t.column("ok").to_pylist())
    assert t.column("failure").to_pylist() == ["", ""]
    D = np.asarray(t.column("p:proximal_link.outer_diameter_m").to_numpy())
    np.testing.assert_array_equal(D, [0.0060, 0.0065])
    joints = case.model.joint_rotations
    for i, d_outer in enumerate(D):
        fe = run_fe(case.with_params(**{"proximal_link.outer_diameter_m": float(d_outer)}), POINTS,
                    levels=("detailed",), mesh="coarse", jobs=1)
        for dname in case.loads.directions:
            c = fe.results["P0"].cases[("detailed", joints, dname)]
            tag = dname.lstrip("+")
            # same code path on the same variant: equal up to (at most) float rounding
            assert t.column(f"k_{tag}_N_per_m")[i].as_py() == pytest.approx(c.load_N / c.deflection_m, rel=1e-9)
            assert t.column(f"defl_{tag}_m")[i].as_py() == pytest.approx(c.deflection_m, rel=1e-9)
    for dname in case.loads.directions:
        k = np.asarray(t.column(f"k_{dname.lstrip('+')}_N_per_m").to_numpy())
        assert k[1] > k[0], f"{dname}: a thicker link tube must stiffen the device"
    shares = np.column_stack([t.column(c).to_numpy() for c in t.column_names if c.startswith("share_")])
    np.testing.assert_allclose(shares.sum(axis=1), 1.0, rtol=1e-12)  # energy shares of a whole
    assert np.all(np.diff(t.column("mass_kg").to_numpy()) > 0)


@pytest.mark.slow
def test_fe_sweep_on_process_pool_is_identical(case, ranges, reference, tmp_path):
    pooled = _fe_sweep(case, ranges, tmp_path, jobs=2)
    assert pooled.manifest["timing"]["backend"] == "process-pool"
    assert pooled.manifest["timing"]["workers"] == 2
    _assert_same(pooled.table, reference.table)


class _Counting:
    """run_fe_task that counts its calls (in-process runs only)."""

    def __init__(self):
        self.calls = 0

    def __call__(self, task):
        self.calls += 1
        return run_fe_task(task)


@pytest.mark.slow
def test_fe_sweep_resumes_a_lost_chunk(case, ranges, reference, tmp_path):
    shutil.copytree(reference.store.root, tmp_path / "r")
    store = SweepStore(tmp_path / "r")
    chunks = store.chunk_files()
    assert len(chunks) == 2
    chunks[1].unlink()  # as if the run had been interrupted before the second sample was stored
    store.results_path.unlink()
    counter = _Counting()
    out = _fe_sweep(case, ranges, store.root, resume=True, task_fn=counter)
    assert counter.calls == 1  # only the lost sample is solved again
    assert out.manifest["resumed_with_finished_samples"] == 1
    _assert_same(out.table, reference.table)
