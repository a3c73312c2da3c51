"""`femcheck verify` fails whenever a law of the analytical model is wrong: each law broken by hand in its own
code, one at a time, must make

    femcheck verify cases/haptic_6psu.toml --level detailed --mesh coarse --points P0,P5

exit 1 with the failing thresholds named, with and without --check; unmutated it exits 0 both ways.

A mutation breaks the analytical law only (monkeypatching its implementation); the FE does not take part in
it. The FE results (device FE, the joints' contact-FE laws, the ball tilt contact FE, the joint table) are
computed once, unmutated, and replayed in every mutated run, which re-runs the analytical model, the tables,
the coverage and the checks. That replay is legitimate only if no FE stage calls a law the mutation patches:
:func:`test_the_fe_stages_call_no_patched_law` records every call into a patched place while an FE stage runs
(the joint check's analytical column, the law the joint FE is compared with, is not part of the FE; in the
replayed runs the joint table keeps its unmutated analytical column, which no threshold reads).

Two unmutated runs are recorded (:data:`RECORDS`). With the joints' contact FE (the default of ``verify``: the
measured joint laws, the ball tilt and the joint table, minutes on a fresh clone; ``make test-all``) no FE stage
reads any patched law, and every mutation is replayed on it. With ``--no-joint-fe`` (the device FE alone, seconds;
the default suite) the FE's joints are the closed-form Hertz and pin laws themselves: a mutation of those moves
the FE alike and no verify run could catch it, so only the other laws' mutations are replayed there, and the test
asserts that the FE reads exactly the joint laws.
"""
from __future__ import annotations

import dataclasses
import importlib
import json

import numpy as np
import pytest

from conftest import REFERENCE_CASE
from femcheck.cli import main

COMMAND = ["verify", str(REFERENCE_CASE), "--level", "detailed", "--mesh", "coarse", "--points", "P0,P5"]

#: the FE stages of a verify run: (module, function); each is run once, unmutated, and replayed afterwards
FE_STAGES = (("femcheck.verify.fe", "run_fe"), ("femcheck.verify.contact_joints", "ball_tilt_study"),
             ("femcheck.fe_device.joint_laws", "measure_joint_laws"), ("femcheck.fe_device.joint_check", "check_joint"))

HERTZ_E_STAR = 3.0 ** -1.5      # k_sp = (6 E*^2 R* F)^(1/3) ~ E*^(2/3): E* x 3^(-3/2) makes the contact 3x more compliant


def _softer(factor):
    return lambda law: (lambda *a, **k: law(*a, **k) / factor)


def _hertz_through_e_star(law):
    return lambda F, E_star, R_star: law(F, E_star * HERTZ_E_STAR, R_star)


def _moments_swapped(law):
    return lambda *a, **k: dataclasses.replace(s := law(*a, **k), Ix=s.Iy, Iy=s.Ix)


#: mutation -> (the law's one implementation (module, attribute), its wrapper). Every consumer, the compiled
#: chain kernels included, reads the law from its module when it runs, so this one place is the whole mutation;
#: the Hertz wrapper is compiled by numba with the kernel (a closure calling the original law).
MUTATIONS = {
    "cable 5x softer": (("femcheck.compliance.actuation", "cable_stiffness"), _softer(5.0)),
    "U-joint pin bending 10x softer": (("femcheck.compliance.hertz_line_contact", "pin_bending_stiffness"), _softer(10.0)),
    "Hertz contact 3x more compliant (E*)": (("femcheck.compliance.hertz_point_contact", "hertz_tangent_stiffness"),
                                             _hertz_through_e_star),
    "motor shaft 5x softer": (("femcheck.compliance.actuation", "motor_stiffness_at_cable"), _softer(5.0)),
    "guideway second moments swapped": (("femcheck.compliance.sections", "rectangle_section"), _moments_swapped),
}


#: the recorded unmutated runs: name -> extra verify options. The contact-FE record is minutes of joint FE on a
#: fresh clone: it runs in the full suite (make test-all); the closed-form one is the default suite's
CLOSED_FORM_JOINTS, CONTACT_FE_JOINTS = "closed-form-joints", "contact-fe-joints"
RECORDS = {CLOSED_FORM_JOINTS: ["--no-joint-fe"], CONTACT_FE_JOINTS: []}
#: the FE stages each record runs (the closed-form one has no joint FE)
RECORD_STAGES = {CLOSED_FORM_JOINTS: {"run_fe"}, CONTACT_FE_JOINTS: {attr for _, attr in FE_STAGES}}
#: mutations of the joints' own laws: with --no-joint-fe the device FE reads them too (shared closed forms), so only
#: the contact-FE record can show that verify catches them
JOINT_LAW_MUTATIONS = ("U-joint pin bending 10x softer", "Hertz contact 3x more compliant (E*)")
#: the element (verify's coverage.json) whose compliance law each mutation breaks
MUTATED_ELEMENT = {"cable 5x softer": "actuation", "U-joint pin bending 10x softer": "universal_joint",
                   "Hertz contact 3x more compliant (E*)": "spherical_joint", "motor shaft 5x softer": "actuation",
                   "guideway second moments swapped": "guideway"}


def _replayable(record: str) -> list[str]:
    """The mutations whose law no FE stage of ``record`` reads."""
    return [m for m in MUTATIONS if record == CONTACT_FE_JOINTS or m not in JOINT_LAW_MUTATIONS]


def _record_param(record: str, *values, id_suffix: str = "", slow: bool = False):
    """A test parameter on ``record`` (indirect: the fixture :func:`fe_record` runs it once per module); the
    contact-FE record's tests are slow."""
    marks = [pytest.mark.slow] if slow or record == CONTACT_FE_JOINTS else []
    return pytest.param(record, *values, id=record + id_suffix, marks=marks)


def _places(name):
    (module, attr), wrap = MUTATIONS[name]
    return [(module, attr, wrap)]


def _apply_mutation(name, monkeypatch) -> None:
    """Break one analytical law (:data:`MUTATIONS`) in its module, for this test only (the caches of case
    parameters are keyed on the law functions, so unmutated runs never see the mutated values)."""
    for module, attr, wrap in _places(name):
        mod = importlib.import_module(module)
        monkeypatch.setattr(mod, attr, wrap(getattr(mod, attr)))


def _verify(capsys, tmp_path, *extra):
    """Run the command in-process; (exit code, stdout lines, verdict.json)."""
    out = tmp_path / "run"
    rc = main(COMMAND + ["--out", str(out), "--force", *extra])
    lines = [ln for ln in capsys.readouterr().out.splitlines() if ln.strip()]
    verdict = json.loads((out / "verdict.json").read_text()) if (out / "verdict.json").is_file() else None
    return rc, lines, verdict


@pytest.fixture(scope="module")
def fe_record(request, tmp_path_factory):
    """The unmutated run of the record ``request.param`` (:data:`RECORDS`), once: every FE stage's result (for the
    replay) and every call an FE stage made into a place a mutation patches (for the legitimacy test). In-process
    solves (--jobs 1) so that calls are seen."""
    record = request.param
    mp = pytest.MonkeyPatch()
    results: dict[str, list] = {}
    law_calls: list[tuple] = []
    depth, comparing = [0], [0]

    def law_spy(where, fn):
        def spy(*a, **k):
            if not comparing[0]:
                law_calls.append(where)
            return fn(*a, **k)
        return spy

    def comparison(fn):
        # the joint check's analytical column is the law the FE is compared with, not part of the FE's set-up
        def spy(*a, **k):
            comparing[0] += 1
            try:
                return fn(*a, **k)
            finally:
                comparing[0] -= 1
        return spy
    joint_fe = importlib.import_module("femcheck.fe_device.joint_fe")
    mp.setattr(joint_fe, "analytical_compliance", comparison(joint_fe.analytical_compliance))

    def stage_spy(attr, fn):
        # the law spies stand in only while an FE stage runs: outside, the compiled kernels take the laws as
        # numba functions (a Python spy there would not compile); inside, a kernel call would fail loudly too
        def spy(*a, **k):
            laws = pytest.MonkeyPatch() if depth[0] == 0 else None
            if laws is not None:
                for name in MUTATIONS:
                    for module, law, _ in _places(name):
                        mod = importlib.import_module(module)
                        laws.setattr(mod, law, law_spy(f"{module}.{law}", getattr(mod, law)))
            depth[0] += 1
            try:
                r = fn(*a, **k)
            finally:
                depth[0] -= 1
                if laws is not None:
                    laws.undo()
            results.setdefault(attr, []).append(r)
            return r
        return spy
    for module, attr in FE_STAGES:
        mod = importlib.import_module(module)
        mp.setattr(mod, attr, stage_spy(attr, getattr(mod, attr)))
    out = tmp_path_factory.mktemp("unmutated")
    try:
        rc = main(COMMAND + ["--out", str(out / "run"), "--jobs", "1", "--no-vtu", *RECORDS[record]])
    finally:
        mp.undo()
    return {"record": record, "rc": rc, "results": results, "law_calls": law_calls,
            "verdict": json.loads((out / "run" / "verdict.json").read_text()),
            "coverage": json.loads((out / "run" / "coverage.json").read_text())}


@pytest.fixture()
def replay_fe(fe_record, monkeypatch):
    """Every FE stage returns its recorded (unmutated) result; a call with other arguments than the recorded
    run's would be a different FE, so each stage replays its calls in order."""
    for module, attr in FE_STAGES:
        queue = list(fe_record["results"].get(attr, []))
        monkeypatch.setattr(importlib.import_module(module), attr,
                            lambda *a, _q=queue, _n=attr, **k: _q.pop(0) if _q else pytest.fail(f"{_n}: not recorded"))


ON_EACH_RECORD = [_record_param(r) for r in RECORDS]


@pytest.mark.parametrize("fe_record", ON_EACH_RECORD, indirect=True)
def test_unmutated_record_run_passes(fe_record):
    assert fe_record["rc"] == 0, fe_record["verdict"]["summary"]
    assert set(fe_record["results"]) == RECORD_STAGES[fe_record["record"]]   # every FE stage ran once at least


@pytest.mark.parametrize("fe_record", ON_EACH_RECORD, indirect=True)
def test_the_fe_stages_call_no_patched_law(fe_record):
    """The replay of a mutation is legitimate only if the FE does not read the law it breaks (the FE set-up comes
    from geometry, materials, friction and loads): no FE stage calls it while it runs, and, by behaviour, the
    record's own coverage finds that the FE does not move when that element's law is scaled (a law read once
    outside a stage and cached would escape the first test, not the second). With the closed-form joints the
    coverage finds the FE moving with the joint laws: the reason their mutations are not replayed there."""
    replayed = _replayable(fe_record["record"])
    called = set(fe_record["law_calls"])
    assert not called & {f"{module}.{attr}" for m in replayed for module, attr, _ in _places(m)}, sorted(called)
    source = {e["element"]: e["fe_source"] for e in fe_record["coverage"]["elements"]}
    assert all(source[MUTATED_ELEMENT[m]] != "shared_closed_form" for m in replayed), source
    if fe_record["record"] == CLOSED_FORM_JOINTS:
        assert {source[MUTATED_ELEMENT[m]] for m in JOINT_LAW_MUTATIONS} == {"shared_closed_form"}, source
    else:
        assert called == set(), sorted(called)


@pytest.mark.parametrize("fe_record, check", [
    _record_param(r, check, id_suffix="-check" if check else "-no-check") for r in RECORDS for check in (False, True)],
    indirect=["fe_record"])
def test_unmutated_exits_0(fe_record, replay_fe, capsys, tmp_path, check):
    rc, lines, verdict = _verify(capsys, tmp_path, *RECORDS[fe_record["record"]], *(["--check"] if check else []))
    assert rc == 0, lines[:1] + lines[-3:]
    assert lines[0].startswith("PASS: ") and lines[-1] == lines[0]
    kinds = {c["kind"] for c in verdict["checks"] if c["status"] == "pass"}
    assert kinds >= ({"threshold", "idealization", "drift"} if check else {"threshold", "idealization"})


#: the --check variant of each mutation adds the drift check to the same failed thresholds: 13 s per run, so it runs
#: in the full suite (make test-all); the default suite keeps one run per mutation it can replay (no --check), each
#: able to fail
@pytest.mark.parametrize("fe_record, mutation, check", [
    _record_param(r, m, check, id_suffix=f"-{m}-{'check' if check else 'no-check'}", slow=check)
    for r in RECORDS for m in _replayable(r) for check in (False, True)], indirect=["fe_record"])
def test_a_broken_law_fails_the_thresholds(fe_record, mutation, check, replay_fe, monkeypatch, capsys, tmp_path):
    """Exit 1, the failed thresholds named on the first and last line and in verdict.json."""
    _apply_mutation(mutation, monkeypatch)
    rc, lines, verdict = _verify(capsys, tmp_path, *RECORDS[fe_record["record"]], *(["--check"] if check else []))
    assert rc == 1, lines[:1]
    failed = [c["name"] for c in verdict["checks"] if c["status"] == "fail" and c["kind"] == "threshold"]
    assert failed, verdict["summary"]                      # a threshold fails, not only the analytical drift
    assert lines[0].startswith("FAIL: ") and lines[-1] == lines[0] and failed[0] in lines[0]
    assert verdict["worst_error"]["mean_error_pct"] > verdict["worst_error"]["threshold_pct"]
    print(f"{fe_record['record']} | {mutation} | --check {check} | exit {rc} | {verdict['summary']}")   # the table of the suite (pytest -rA)


def test_the_mutation_reaches_the_analytical_model_by_its_law():
    """Each mutation moves the analytical deflection at P0 (both backends alike: the compiled kernel and the
    numpy reference), by the amount its law implies where it is closed-form."""
    import femcheck
    from femcheck.chain import evaluate
    from femcheck.kinematics.points import point_set
    case = femcheck.load_case(str(REFERENCE_CASE))
    pts = point_set(case, ("P0",))
    W = np.r_[15.0, 0, 0, 0, 0, 0]

    def run(backend):
        r = evaluate(case, pts.poses, W, model="detailed", joints="released", legs=pts.legs, backend=backend)
        return r.twist[0, 0], r.k_sp[0]
    base = run("compiled")
    for name in MUTATIONS:
        with pytest.MonkeyPatch.context() as mp:
            _apply_mutation(name, mp)
            compiled, numpy_ref = run("compiled"), run("numpy")
        assert compiled[0] == pytest.approx(numpy_ref[0], rel=1e-9), name   # both backends see the same law
        assert abs(compiled[0] / base[0] - 1) > 0.01, name                    # the law moved the model
        if name.startswith("Hertz"):
            # 3x compliance at the same force; the joint forces barely move under released joints (statics)
            np.testing.assert_allclose(compiled[1], base[1] / 3, rtol=1e-6)
