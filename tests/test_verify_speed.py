"""What makes `femcheck verify` fast must not change what it computes.

* The ball tilt contact FE on the bodies condensed onto the Hertz-band contact DOFs gives the moment, normal force
  and slip of the whole-mesh solve (static condensation is exact for linear bodies; the dropped points stay open).
* The result cache returns what was stored, under a key that changes with every input and with the FE code; a
  corrupt entry is computed again; a cached super-element is the computed one, bit for bit, and is read without
  meshing.
* The verify progress plan keeps the ETA within 3x of the time left after a tenth of the work, on the stage
  costs of measured cold and warm runs (fake clock).
* With MKL hidden (``FEMCHECK_NO_PARDISO=1``, as on ARM machines) the automatic solver is CHOLMOD/UMFPACK.
"""
from __future__ import annotations

import dataclasses
import io
import os
import subprocess
import sys

import numpy as np
import pytest
from rich.console import Console

from conftest import REFERENCE_CASE
from femcheck.cli._progress import StageProgress


@pytest.fixture(scope="module")
def case():
    import femcheck
    return femcheck.load_case(str(REFERENCE_CASE))


#: a mesh of the ball in its seat far coarser than the study's (TILT_SIZE_M = 2 mm), so the whole-mesh solve is quick
#: (at 6 mm the condensed band holds too few contact nodes and its Newton stalls with a ConvergenceError)
COARSE_TILT_SIZE_M = 0.005


@pytest.mark.slow   # the whole-mesh solve: 55 s frictionless, 280 s with friction at load 9 (the default suite keeps
#                    the band check below; the study's own mesh agreed to 8 digits in M and N, 0.96370958 slip ratio)
@pytest.mark.parametrize("mu", [0.0, 0.2], ids=["frictionless", "friction"])
def test_condensed_tilt_is_the_whole_mesh_solve(case, mu):
    from femcheck.fe_device.joint_contact import spherical_joint_tilt
    kw = dict(friction=mu, size_m=COARSE_TILT_SIZE_M)
    whole = spherical_joint_tilt(case, 20.0, 0.01, condensed=False, **kw)
    cond = spherical_joint_tilt(case, 20.0, 0.01, condensed=True, **kw)
    # same equations, same Newton and Uzawa tolerances (penetration 1e-3 of the approach, rtol 1e-8): the
    # states agree to the solver tolerance, far below the 1 % the tilt slip ratio is read to
    assert cond.normal_force_N == pytest.approx(whole.normal_force_N, rel=1e-6)
    scale = mu * 20.0 * cond.ball_radius_m if mu else 1e-6   # the slip moment; frictionless: a round-off remainder
    assert np.max(np.abs(cond.moment_Nm - whole.moment_Nm)) <= 1e-5 * scale + 1e-12
    assert np.array_equal(cond.slip_fraction, whole.slip_fraction)
    assert cond.dofs == whole.dofs                               # the same model (free unknowns of the mesh)


def test_condensed_tilt_refuses_a_band_that_misses_a_contact(case, monkeypatch):
    """A band too narrow to hold the contact patch is an error naming it, never a silently wrong moment."""
    from femcheck.errors import ConvergenceError
    from femcheck.fe_device import joint_contact as jc
    monkeypatch.setattr(jc, "TILT_BAND", 0.0)   # the first points to touch only: the patch grows beyond them
    with pytest.raises(ConvergenceError, match="outside the Hertz band"):
        jc.spherical_joint_tilt(case, 20.0, 0.01, friction=0.0, size_m=COARSE_TILT_SIZE_M)


def test_result_cache_round_trip_key_and_corrupt_entry(tmp_path, monkeypatch):
    from femcheck.fe import result_cache as rc
    monkeypatch.setenv("FEMCHECK_CACHE", str(tmp_path))
    k = rc.result_key("kind", {"a": 1.0, "b": "x"})
    assert rc.load("kind", k) is None and not rc.has("kind", k)
    value = {"K": np.arange(6.0).reshape(2, 3), "s": "text"}
    rc.store("kind", k, value)
    back = rc.load("kind", k)
    assert np.array_equal(back["K"], value["K"]) and back["s"] == "text"
    assert rc.result_key("kind", {"a": 1.0 + 1e-12, "b": "x"}) != k       # any input changes the key
    assert rc.result_key("other", {"a": 1.0, "b": "x"}) != k
    monkeypatch.setattr(rc, "_source_hash", lambda: "changed code")       # and so does the FE code
    assert rc.result_key("kind", {"a": 1.0, "b": "x"}) != k
    monkeypatch.undo()
    monkeypatch.setenv("FEMCHECK_CACHE", str(tmp_path))
    (tmp_path / "kind" / f"{k}.pkl").write_bytes(b"not a pickle")
    assert rc.load("kind", k) is None                                     # computed again, never trusted
    monkeypatch.setenv(rc.ENV_OFF, "1")
    rc.store("kind", k, value)
    assert rc.load("kind", k) is None


def test_cached_superelement_is_the_computed_one_and_needs_no_mesh(case, tmp_path, monkeypatch):
    from femcheck.fe_device import parts
    from femcheck.fe_device.mesh_levels import mesh_sizes
    from geometry import guideway
    monkeypatch.setenv("FEMCHECK_CACHE", str(tmp_path))
    size = mesh_sizes(case, "coarse").guideway_m
    first = parts.guideway_element(case, 0.06, "solid", size)
    assert not first.cached

    def no_mesh(*a, **k):
        raise AssertionError("a cached super-element must not be meshed again")
    monkeypatch.setattr(guideway, "build", no_mesh)
    again = parts.guideway_element(case, 0.06, "solid", size)
    assert again.cached and again.assembly_s == 0.0
    for f in ("K", "recovery", "vertices", "tets"):
        assert np.array_equal(getattr(again, f), getattr(first, f)), f
    # another mesh size (same length, same couplings) is another mesh: computed, so here it would have to be meshed
    with pytest.raises(AssertionError, match="must not be meshed"):
        parts.guideway_element(case, 0.06, "solid", 0.9 * size)


# stage costs (s) of measured runs in the order run_verify reports them, from their manifest.json timings_s: `femcheck
# verify cases/haptic_6psu.toml --check` (what make verify runs: nine points, default mesh) cold at load average 3-6
# and warm at load 2-3, and the coarse P0, P5 run warm at load 10. A stage's total is measured; its split over its
# steps (link vs guideways, build vs solve, the two joints) follows the stage's sizes, and the guideways finish
# in any order with the link (--jobs 2).
COLD_RUN = {"tilt": [3.8, 3.8], "law:spherical": [20.0], "law:universal": [37.1], "table:spherical": [17.0, 2.5],
            "table:universal": [0.3, 0.7], "fe:default": [8.0] + [1.03] * 54, "figures": [8.1], "diagnosis": [28.7],
            "coverage": [3.8], "fe:coarse": [1.0] + [0.3] * 6, "fe:fine": [12.0] + [3.1] * 6, "report": [1.0]}
WARM_RUN = {"tilt": [0.005, 0.005], "law:spherical": [0.005], "law:universal": [0.005],
            "table:spherical": [0.001, 0.001], "table:universal": [0.001, 0.001], "fe:default": [0.016] * 55,
            "figures": [7.5], "diagnosis": [27.3], "coverage": [3.9], "fe:coarse": [0.016] * 7, "fe:fine": [0.016] * 7,
            "report": [1.0]}
WARM_COARSE_RUN = {"tilt": [0.02, 0.01], "law:spherical": [0.01], "law:universal": [0.01],
                   "table:spherical": [0.01, 0.01], "table:universal": [0.01, 0.01], "fe:coarse": [0.085] * 13,
                   "figures": [13.8], "coverage": [4.7], "report": [1.0]}


def _worst_eta_ratio(steps, weights, work_of) -> float:
    """Run the stage on a fake clock, steps (description, true cost s) in order; the worst max(eta/left, left/eta)
    once a tenth of the true time has passed."""
    clock = [0.0]
    total = float(sum(c for _, c in steps))
    worst = 1.0
    with StageProgress("verify", None, Console(file=io.StringIO()), tty=False, interval_s=1e9, weights=weights,
                       clock=lambda: clock[0]) as bar:
        for k, (desc, cost) in enumerate(steps):
            clock[0] += cost
            bar.advance(1, desc, work=work_of(desc))
            left, eta = total - clock[0], bar.eta_s()
            if clock[0] >= 0.1 * total and k < len(steps) - 1:
                worst = max(worst, eta / left, left / eta)
    return worst


def _steps(run: dict, guideway_first: bool = False) -> list:
    """(description, cost) in report order; the device FE's guideways may finish before its link (--jobs 2)."""
    out = []
    for phase, costs in run.items():
        if phase.startswith("fe:"):
            descs = ["link"] + [f"P0 guideway {i}" for i in range(len(costs) - 1)]
            pairs = list(zip(descs, costs))
            if guideway_first:
                pairs = pairs[1:4] + pairs[:1] + pairs[4:]
            out += pairs
        else:
            out += [(phase, c) for c in costs]
    return out


@pytest.mark.parametrize("guideway_first", [False, True], ids=["link-first", "guideways-first"])
def test_verify_eta_within_3x_on_measured_cold_and_warm_runs(case, monkeypatch, guideway_first):
    from femcheck.verify import progress_plan as pp
    from femcheck.kinematics.psu6 import POINT_LABELS
    for warm, run, points, mesh, conv in ((False, COLD_RUN, POINT_LABELS, "default", "P0"),
                                          (True, WARM_RUN, POINT_LABELS, "default", "P0"),
                                          (True, WARM_COARSE_RUN, ("P0", "P5"), "coarse", None)):
        monkeypatch.setattr("femcheck.verify.contact_joints.tilt_cached", lambda c, w=warm: w)
        monkeypatch.setattr("femcheck.fe_device.joint_laws.cached",
                            lambda c, m, w=warm: {"spherical": w, "universal": w})
        monkeypatch.setattr(pp, "joint_table_cached", lambda c, m, w=warm: {"spherical": w, "universal": w})
        work = pp.plan(case, points, ("detailed",), mesh, True, "coarse", conv)
        steps = _steps(run, guideway_first)
        assert len(work.weights) == len(steps)                # the plan has one weight per reported step
        ratio = _worst_eta_ratio(steps, work.weights, work)
        assert ratio <= 3.0, (warm, ratio)                    # the bound after the first 10 % of the work
        # without the cache prediction (cold weights on a warm run) the ETA is far off: the prediction matters
        if warm:
            monkeypatch.setattr("femcheck.verify.contact_joints.tilt_cached", lambda c: False)
            monkeypatch.setattr("femcheck.fe_device.joint_laws.cached", lambda c, m: {"spherical": False, "universal": False})
            monkeypatch.setattr(pp, "joint_table_cached", lambda c, m: {"spherical": False, "universal": False})
            cold = pp.plan(case, points, ("detailed",), mesh, True, "coarse", conv)
            assert _worst_eta_ratio(steps, cold.weights, cold) > 3.0


def test_hidden_mkl_takes_cholmod():
    """FEMCHECK_NO_PARDISO=1 is the solver path of a machine without MKL: "auto" resolves to CHOLMOD (symmetric)
    and UMFPACK (unsymmetric), in a fresh process (the availability check is cached per process)."""
    code = ("from femcheck.fe import linear_solver as ls; import scipy.sparse as sp; "
            "print(ls.pardiso_available(), ls.choose_method(10, True), ls.choose_method(10, False), "
            "ls.factorize(sp.identity(4, format='csr')).method)")
    env = {**os.environ, "FEMCHECK_NO_PARDISO": "1"}
    env.pop("FEMCHECK_LINEAR_SOLVER", None)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "cholmod", "umfpack", "cholmod"]


def test_bench_times_a_command_tree_and_its_peak_memory(tmp_path):
    """The verify bench's timer: wall time, exit code and the peak resident memory of the whole process tree (a child
    holding 400 MB is seen), with the load average beside it."""
    from femcheck.bench.verify import timed
    child = "import numpy as np, time; a = np.ones(50_000_000); time.sleep(1.5)"
    cmd = [sys.executable, "-c", f"import subprocess, sys; sys.exit(subprocess.call([sys.executable, '-c', {child!r}]))"]
    r = timed(cmd, tmp_path, dict(os.environ), tmp_path / "log.txt")
    assert r["rc"] == 0 and r["seconds"] >= 1.5
    assert r["peak_gb"] >= 0.35                     # 50e6 float64 = 0.37 GiB in the grandchild
    assert r["load_average"] >= 0.0


def test_bench_steps_are_checked(monkeypatch):
    from femcheck.bench import verify as bv
    from femcheck.errors import FemcheckError
    monkeypatch.setenv("FEMCHECK_BENCH_VERIFY_STEPS", "cold,warm")
    assert bv._steps() == ("cold", "warm")
    monkeypatch.setenv("FEMCHECK_BENCH_VERIFY_STEPS", "cold,lukewarm")
    with pytest.raises(FemcheckError, match="lukewarm"):
        bv._steps()


def test_validation_page_shows_the_verify_bench_keys():
    """The page generator takes reports/bench/verify.json as the bench writes it: every flat key with the command
    that measured it, the per-figure load averages as detail in the JSON (shape only: no figure here is quoted)."""
    from femcheck.bench.validation_page import render
    keys = ("make_verify_cold_s", "make_verify_warm_s", "install_s", "make_verify_nomkl_s", "nomkl_peak_gb",
            "test_suite_s", "ball_tilt_s")
    fig = {"bench_wall_s": 1.0, "machine": "cpu", "machine_cpus": 2, "load_average": 0.5,
           **{k: float(i) for i, k in enumerate(keys)}, "verify_stage_s": {"coverage": 1.0},
           "load_average_by_figure": {k: 0.5 for k in keys}}
    page = render({"verify": fig})
    for k in keys:
        assert f"`{k}` |" in page, k
    for k, cmd in (("make_verify_cold_s", "make verify"), ("test_suite_s", "make test"), ("install_s", "make venv")):
        assert f"`{k}` | {float(keys.index(k)):g} (`{cmd}`" in page
    assert "`load_average_by_figure`" in page and "load average 0.5" in page
