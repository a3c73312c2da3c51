"""`femcheck verify` fails whenever a law of the analytical model is wrong: each law broken by hand in its own
code, one at a time, must make

    femcheck verify cases/haptic_6psu.toml --level detailed --mesh coarse --points P0,P5

exit 1 with the failing thresholds named, with and without --check; unmutated it exits 0 both ways.

A mutation breaks the analytical law only (monkeypatching its implementation); the FE does not take part in
it. The FE results (device FE, the joints' contact-FE laws, the ball tilt contact FE, the joint table) are
computed once, unmutated, and replayed in every mutated run, which re-runs the analytical model, the tables,
the coverage and the checks. That replay is legitimate only if no FE stage calls a law the mutations patch:
:func:`test_the_fe_stages_call_no_patched_law` records every call into a patched place while an FE stage runs.
"""
from __future__ import annotations

import dataclasses
import functools
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


def _kernel_e_star(pack):
    """The compiled chain kernel's own Hertz copy (``_hertz_k``) reads E* from the packed parameter table."""
    from femcheck.chain import haptic_6psu_kernel as kern

    def packed(p, n):
        out = pack(p, n)
        out[:, kern.P_ESTAR] *= HERTZ_E_STAR
        return out
    return packed


#: mutation -> (the law's implementation, its wrapper, the other places that hold the law in this code base).
#: The first place is the law's own module; the extra places are by-name imports of it and, for the Hertz law,
#: the compiled kernel's private copy reached through the E* it is given. Once every consumer reads the law
#: from its module, the extra places go.
MUTATIONS = {
    "cable 5x softer": (("femcheck.compliance.actuation", "cable_stiffness"), _softer(5.0),
                        [("femcheck.compliance", "cable_stiffness"),
                         ("femcheck.chain.device_parameters", "cable_stiffness")]),
    "U-joint pin bending 10x softer": (("femcheck.compliance.hertz_line_contact", "pin_bending_stiffness"), _softer(10.0),
                                       [("femcheck.compliance", "pin_bending_stiffness"),
                                        ("femcheck.chain.device_parameters", "pin_bending_stiffness")]),
    "Hertz contact 3x more compliant (E*)": (("femcheck.compliance.hertz_point_contact", "hertz_tangent_stiffness"),
                                             _hertz_through_e_star,
                                             [("femcheck.compliance", "hertz_tangent_stiffness"),
                                              ("femcheck.chain.haptic_6psu_model", "hertz_tangent_stiffness"),
                                              ("femcheck.chain.haptic_6psu_model", "pack_parameters", _kernel_e_star)]),
    "motor shaft 5x softer": (("femcheck.compliance.actuation", "motor_stiffness_at_cable"), _softer(5.0),
                              [("femcheck.compliance", "motor_stiffness_at_cable"),
                               ("femcheck.chain.device_parameters", "motor_stiffness_at_cable")]),
    "guideway second moments swapped": (("femcheck.compliance.sections", "rectangle_section"), _moments_swapped,
                                        [("femcheck.compliance", "rectangle_section"),
                                         ("femcheck.chain.device_parameters", "rectangle_section")]),
}


def _places(name):
    law, wrap, extra = MUTATIONS[name]
    return [(law[0], law[1], wrap)] + [(p[0], p[1], p[2] if len(p) > 2 else wrap) for p in extra]


def _apply_mutation(name, monkeypatch) -> None:
    """Break one analytical law (:data:`MUTATIONS`) at every place that holds it, for this test only. The compiled
    path caches each case's parameters (``_case_constants``); a fresh cache, dropped on undo, keeps the mutated
    parameters out of the unmutated runs."""
    for module, attr, wrap in _places(name):
        mod = importlib.import_module(module)
        monkeypatch.setattr(mod, attr, wrap(getattr(mod, attr)))
    model = importlib.import_module("femcheck.chain.haptic_6psu_model")
    monkeypatch.setattr(model, "_case_constants", functools.lru_cache(maxsize=32)(model._case_constants.__wrapped__))


def _verify(capsys, tmp_path, *extra):
    """Run the command in-process; (exit code, stdout lines, verdict.json)."""
    out = tmp_path / "run"
    rc = main(COMMAND + ["--out", str(out), "--force", *extra])
    lines = [ln for ln in capsys.readouterr().out.splitlines() if ln.strip()]
    verdict = json.loads((out / "verdict.json").read_text()) if (out / "verdict.json").is_file() else None
    return rc, lines, verdict


@pytest.fixture(scope="module")
def fe_record(tmp_path_factory):
    """The unmutated run, once: every FE stage's result (for the replay) and every call an FE stage made into a
    place a mutation patches (for the legitimacy test). In-process solves (--jobs 1) so that calls are seen."""
    mp = pytest.MonkeyPatch()
    results: dict[str, list] = {}
    law_calls: list[tuple] = []
    depth = [0]

    def stage_spy(attr, fn):
        def spy(*a, **k):
            depth[0] += 1
            try:
                r = fn(*a, **k)
            finally:
                depth[0] -= 1
            results.setdefault(attr, []).append(r)
            return r
        return spy

    def law_spy(where, fn):
        def spy(*a, **k):
            if depth[0]:
                law_calls.append(where)
            return fn(*a, **k)
        return spy
    for module, attr in FE_STAGES:
        mod = importlib.import_module(module)
        mp.setattr(mod, attr, stage_spy(attr, getattr(mod, attr)))
    for name in MUTATIONS:
        for module, attr, _ in _places(name):
            mod = importlib.import_module(module)
            mp.setattr(mod, attr, law_spy(f"{module}.{attr}", getattr(mod, attr)))
    out = tmp_path_factory.mktemp("unmutated")
    try:
        rc = main(COMMAND + ["--out", str(out / "run"), "--jobs", "1", "--no-vtu"])
    finally:
        mp.undo()
    return {"rc": rc, "results": results, "law_calls": law_calls,
            "verdict": json.loads((out / "run" / "verdict.json").read_text())}


@pytest.fixture()
def replay_fe(fe_record, monkeypatch):
    """Every FE stage returns its recorded (unmutated) result; a call with other arguments than the recorded
    run's would be a different FE, so each stage replays its calls in order."""
    for module, attr in FE_STAGES:
        queue = list(fe_record["results"].get(attr, []))
        monkeypatch.setattr(importlib.import_module(module), attr,
                            lambda *a, _q=queue, _n=attr, **k: _q.pop(0) if _q else pytest.fail(f"{_n}: not recorded"))


def test_unmutated_record_run_passes(fe_record):
    assert fe_record["rc"] == 0, fe_record["verdict"]["summary"]
    assert set(fe_record["results"]) == {attr for _, attr in FE_STAGES}   # every FE stage ran once at least


@pytest.mark.xfail(strict=True, reason="the device FE still reads femcheck.chain.device_parameters (solve_point, "
                   "joint_friction, the joint contact FE's analytical compliance): the FE set-up is not yet independent "
                   "of the analytical laws; strict, so the mark must go once it is")
def test_the_fe_stages_call_no_patched_law(fe_record):
    """The replay is legitimate only if no FE stage reads a law the mutations break (the FE set-up comes from
    geometry, materials, friction and loads)."""
    assert fe_record["law_calls"] == [], sorted(set(fe_record["law_calls"]))


@pytest.mark.parametrize("check", [False, True], ids=["no-check", "check"])
def test_unmutated_exits_0(replay_fe, capsys, tmp_path, check):
    rc, lines, verdict = _verify(capsys, tmp_path, *(["--check"] if check else []))
    assert rc == 0, lines[:1] + lines[-3:]
    assert lines[0].startswith("PASS: ") and lines[-1] == lines[0]
    kinds = {c["kind"] for c in verdict["checks"] if c["status"] == "pass"}
    assert kinds >= ({"threshold", "idealization", "drift"} if check else {"threshold", "idealization"})


@pytest.mark.parametrize("check", [False, True], ids=["no-check", "check"])
@pytest.mark.parametrize("mutation", list(MUTATIONS))
def test_a_broken_law_fails_the_thresholds(mutation, check, replay_fe, monkeypatch, capsys, tmp_path):
    """Exit 1, the failed thresholds named on the first and last line and in verdict.json."""
    _apply_mutation(mutation, monkeypatch)
    rc, lines, verdict = _verify(capsys, tmp_path, *(["--check"] if check else []))
    assert rc == 1, lines[:1]
    failed = [c["name"] for c in verdict["checks"] if c["status"] == "fail" and c["kind"] == "threshold"]
    assert failed, verdict["summary"]                      # a threshold fails, not only the analytical drift
    assert lines[0].startswith("FAIL: ") and lines[-1] == lines[0] and failed[0] in lines[0]
    assert verdict["worst_error"]["mean_error_pct"] > verdict["worst_error"]["threshold_pct"]
    print(f"{mutation} | --check {check} | exit {rc} | {verdict['summary']}")   # the table of the suite (pytest -rA)


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
