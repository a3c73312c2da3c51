"""Bad input, each in the table below: the exit code, one line on stderr that names the
culprit, no traceback, the inputs unmodified, and no output left behind. Good inputs beside them exit 0.

Runs ``femcheck.cli.main`` in-process (the same function the console script calls; its exit-code path
is tested through a real subprocess in ``test_exit_codes.py``).
"""
from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import pytest

from femcheck.cli import main

ROOT = Path(__file__).resolve().parents[1]
#: a pose at a constraint singularity of the reference device (cond(J_h) ~ 1.5e6), found by a random search
SINGULAR_POSE = "0.02005724,-0.03464544,0.36387856,-0.40609716,0.63678694,-0.5940028"


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """Copies of the user's inputs (case files, a measured CSV, a PNG, a plain file) in one folder."""
    d = tmp_path_factory.mktemp("inputs")
    for name in ("haptic_6psu.toml", "irb120.toml", "hiss.toml", "humanoid_tree.toml"):
        shutil.copy(ROOT / "cases" / name, d / name)
    shutil.copy(ROOT / "docs" / "images" / "spherical_joint.png", d / "picture.png")
    (d / "a_file").write_text("not a folder\n")
    (d / "existing_report").write_text("a file where a folder is asked for\n")
    bad = (d / "haptic_6psu.toml").read_text().replace("outer_diameter_m = ", "outer_diameter_m = -", 1)
    (d / "negative.toml").write_text(bad)
    assert main(["experiment", "simulate", str(d / "haptic_6psu.toml"), "--out", str(d / "measured.csv"),
                 "--truth", str(d / "truth.json"), "--directions", "+x,+z", "--no-sweep"]) == 0
    lines = (d / "measured.csv").read_text().splitlines()
    header = [ln for ln in lines if not ln.startswith("#")][0]
    (d / "no_column.csv").write_text("\n".join([header.replace(",dz_mm", "")] + [ln.rsplit(",", 1)[0] for ln in lines[4:]]))
    assert main(["experiment", "simulate", str(d / "humanoid_tree.toml"), "--out", str(d / "positions.csv"),
                 "--truth", str(d / "positions_truth.json"), "--poses", "12"]) == 0
    (d / "robot.urdf").write_text("<robot name='r'><link name='a'/><link name='b'><inertial><mass value='1'/></inertial>"
                                  "</link><joint name='j' type='revolute'><parent link='a'/><child link='b'/>"
                                  "<axis xyz='0 0 1'/></joint></robot>")
    (d / "user_folder").mkdir()
    (d / "user_folder" / "notes.txt").write_text("mine\n")
    return d


# (id, argv with {d} for the inputs folder, expected exit code, text the one error line must contain,
#  output path that must not exist afterwards or None)
CASES = [
    ("case_is_png", ["stiffness", "{d}/picture.png"], 2, "not a text file", None),
    ("negative_diameter", ["stiffness", "{d}/negative.toml"], 2, "outer_diameter_m", None),
    ("pose_nan", ["stiffness", "{d}/haptic_6psu.toml", "--pose", "nan,0,0.375,0,0,0"], 2, "--pose", None),
    ("wrench_inf", ["stiffness", "{d}/haptic_6psu.toml", "--wrench", "inf,0,0,0,0,0"], 2, "--wrench", None),
    ("pose_singular", ["stiffness", "{d}/haptic_6psu.toml", "--pose", SINGULAR_POSE], 2, "cond(J_h)", None),
    ("pose_unreachable", ["stiffness", "{d}/haptic_6psu.toml", "--pose", "0.3,0,0.375,0,0,0"], 2, "unreachable", None),
    ("stiffness_of_serial_robot", ["stiffness", "{d}/irb120.toml"], 2, "meta.kind", None),
    ("verify_of_parallel_vjm", ["verify", "{d}/hiss.toml", "--level", "none", "--out", "{d}/v_hiss"], 2, "meta.kind", "{d}/v_hiss"),
    ("diagnose_of_serial_robot_without_masses", ["diagnose", "{d}/irb120.toml", "{d}/measured.csv"], 2, "mass_kg", None),
    ("verify_out_unwritable", ["verify", "{d}/haptic_6psu.toml", "--level", "none", "--out", "{d}/a_file/run"], 2, "--out", None),
    ("verify_out_user_folder", ["verify", "{d}/haptic_6psu.toml", "--level", "none", "--out", "{d}/user_folder"], 2, "--force", None),
    ("verify_out_holds_case", ["verify", "{d}/haptic_6psu.toml", "--level", "none", "--out", "{d}", "--force"], 2, "holds the input", None),
    ("verify_missing_baseline", ["verify", "{d}/haptic_6psu.toml", "--level", "none", "--check", "--baseline", "{d}/nope.json",
                                 "--out", "{d}/v_nobase"], 2, "--baseline", "{d}/v_nobase"),
    ("map_out_unwritable", ["map", "{d}/haptic_6psu.toml", "--out", "{d}/a_file/m.png"], 2, "--out", None),
    ("map_out_not_png", ["map", "{d}/haptic_6psu.toml", "--out", "{d}/m.txt"], 2, ".png", "{d}/m.txt"),
    ("map_resolution_0", ["map", "{d}/haptic_6psu.toml", "--out", "{d}/m0.png", "--resolution", "0"], 2, "--resolution", "{d}/m0.png"),
    ("map_resolution_negative", ["map", "{d}/haptic_6psu.toml", "--out", "{d}/m5.png", "--resolution", "-5"], 2, "--resolution", "{d}/m5.png"),
    ("map_nothing_reachable", ["map", "{d}/haptic_6psu.toml", "--out", "{d}/mz.png", "--z", "5"], 2, "reachable", "{d}/mz.png"),
    ("mesh_size_zero", ["mesh", "{d}/haptic_6psu.toml", "--part", "guideway", "--out", "{d}/g0.vtu", "--size", "0"], 2, "--size", "{d}/g0.vtu"),
    ("mesh_size_tiny", ["mesh", "{d}/haptic_6psu.toml", "--part", "guideway", "--out", "{d}/g1.vtu", "--size", "1e-5"], 2, "--size", "{d}/g1.vtu"),
    ("simulate_out_unwritable", ["experiment", "simulate", "{d}/haptic_6psu.toml", "--out", "{d}/a_file/x.csv",
                                 "--truth", "{d}/t2.json"], 2, "--out", "{d}/t2.json"),
    ("diagnose_json_unwritable", ["diagnose", "{d}/haptic_6psu.toml", "{d}/measured.csv", "--json", "{d}/a_file/d.json"], 2, "--json", None),
    ("diagnose_report_is_a_file", ["diagnose", "{d}/haptic_6psu.toml", "{d}/measured.csv", "--report", "{d}/existing_report"], 2, "--report", None),
    ("diagnose_missing_column", ["diagnose", "{d}/haptic_6psu.toml", "{d}/no_column.csv"], 2, "dz_mm", None),
    ("unknown_option", ["stiffness", "{d}/haptic_6psu.toml", "--nope"], 2, "--nope", None),
    ("max_condition_nan", ["stiffness", "{d}/haptic_6psu.toml", "--max-condition", "nan"], 2, "--max-condition", None),
    ("coverage_mutation_zero", ["coverage", "{d}/haptic_6psu.toml", "--mutation", "0", "--json", "{d}/c0.json"], 2,
     "--mutation", "{d}/c0.json"),
    ("coverage_bad_point", ["coverage", "{d}/haptic_6psu.toml", "--points", "P9", "--json", "{d}/c1.json"], 2,
     "--points", "{d}/c1.json"),
    ("coverage_bad_mesh", ["coverage", "{d}/haptic_6psu.toml", "--mesh", "medium"], 2, "--mesh", None),
    ("coverage_of_serial_robot", ["coverage", "{d}/irb120.toml"], 2, "meta.kind", None),
    ("coverage_bad_joint_mesh", ["coverage", "{d}/haptic_6psu.toml", "--joint-mesh", "medium", "--json", "{d}/c2.json"],
     2, "--joint-mesh", "{d}/c2.json"),
    ("verify_bad_joint_mesh", ["verify", "{d}/haptic_6psu.toml", "--joint-mesh", "medium", "--out", "{d}/v_jm"], 2,
     "--joint-mesh", "{d}/v_jm"),
    ("check_joints_extended_case_one_joint", ["check-joints", "{d}/haptic_6psu.toml", "--joint", "spherical",
                                              "--extended-case", "{d}/ext.toml"], 2, "--joint all", "{d}/ext.toml"),
    ("check_joints_extended_case_over_input", ["check-joints", "{d}/haptic_6psu.toml", "--extended-case",
                                               "{d}/haptic_6psu.toml"], 2, "input file", None),
    ("coverage_json_unwritable", ["coverage", "{d}/haptic_6psu.toml", "--json", "{d}/a_file/c.json"], 2, "--json", None),
    ("identify_of_6psu", ["identify", "{d}/haptic_6psu.toml", "{d}/measured.csv"], 2, "meta.kind", None),
    ("plan_of_serial_robot", ["plan", "{d}/irb120.toml", "{d}/measured.csv"], 2, "meta.kind", None),
    ("plan_unknown_effect", ["plan", "{d}/haptic_6psu.toml", "{d}/measured.csv", "--effects", "bogus", "--json",
                             "{d}/p0.json"], 2, "bogus", "{d}/p0.json"),
    ("plan_budget_zero", ["plan", "{d}/haptic_6psu.toml", "{d}/measured.csv", "--budget", "0"], 2, "--budget", None),
    ("plan_max_condition_1", ["plan", "{d}/haptic_6psu.toml", "{d}/measured.csv", "--max-condition", "1"], 2,
     "--max-condition", None),
    ("plan_missing_column", ["plan", "{d}/haptic_6psu.toml", "{d}/no_column.csv"], 2, "dz_mm", None),
    ("unknown_linear_solver", ["--linear-solver", "bogus", "stiffness", "{d}/haptic_6psu.toml"], 2, "bogus", None),
    ("serial_diagnose_negative_sigma", ["diagnose", "{d}/humanoid_tree.toml", "{d}/positions.csv", "--sigma-mm", "-1",
                                        "--json", "{d}/s0.json"], 2, "--sigma-mm", "{d}/s0.json"),
    ("serial_diagnose_one_fold", ["diagnose", "{d}/humanoid_tree.toml", "{d}/positions.csv", "--folds", "1"], 2,
     "--folds", None),
    ("serial_diagnose_dial_csv", ["diagnose", "{d}/humanoid_tree.toml", "{d}/measured.csv"], 2, "dial-readings CSV", None),
    ("serial_simulate_unknown_cause", ["experiment", "simulate", "{d}/humanoid_tree.toml", "--effect", "bogus:r2=1e-4",
                                       "--out", "{d}/s1.csv", "--truth", "{d}/s1.json"], 2, "bogus", "{d}/s1.csv"),
    ("serial_simulate_unknown_joint", ["experiment", "simulate", "{d}/humanoid_tree.toml", "--effect",
                                       "joint_torsion_compliance:r99=1e-4", "--out", "{d}/s2.csv", "--truth", "{d}/s2.json"],
     2, "r99", "{d}/s2.csv"),
    ("serial_simulate_unknown_foreign", ["experiment", "simulate", "{d}/humanoid_tree.toml", "--foreign", "wobble=1",
                                         "--out", "{d}/s3.csv", "--truth", "{d}/s3.json"], 2, "wobble", "{d}/s3.csv"),
    ("import_urdf_bad_marker", ["import-urdf", "{d}/robot.urdf", "--marker", "tip=b@1,2", "--out", "{d}/r.toml"], 2,
     "--marker", "{d}/r.toml"),
    ("import_urdf_marker_on_base", ["import-urdf", "{d}/robot.urdf", "--marker", "tip=a", "--out", "{d}/r.toml"], 2,
     "fixed to the base", "{d}/r.toml"),
    ("import_urdf_not_xml", ["import-urdf", "{d}/a_file", "--marker", "tip=b", "--out", "{d}/r.toml"], 2,
     "not a readable URDF", "{d}/r.toml"),
]


def _digests(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.iterdir() if p.is_file()}


@pytest.mark.parametrize("name,argv,code,culprit,absent", CASES, ids=[c[0] for c in CASES])
def test_bad_input(inputs, capsys, name, argv, code, culprit, absent):
    before = _digests(inputs)
    rc = main([a.format(d=inputs) for a in argv])
    out, err = capsys.readouterr()
    assert rc == code, out[-1500:] + err[-1500:]
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err                              # one line ...
    assert lines[0].startswith("error: ") and culprit in lines[0], lines[0]   # ... naming the culprit
    assert "Traceback" not in out + err
    assert _digests(inputs) == before                        # no input touched
    if absent:
        assert not Path(absent.format(d=inputs)).exists()    # no partial output


def test_near_singular_pose_is_answered_with_a_warning(inputs, capsys, tmp_path):
    out = tmp_path / "k.json"
    rc = main(["stiffness", str(inputs / "haptic_6psu.toml"), "--point", "P0", "--max-condition", "30", "--json", str(out)])
    assert rc == 0
    doc = json.loads(out.read_text())
    assert doc["condition_number"] == pytest.approx(3.7665, rel=1e-3)  # docs/conventions.md §3: 3.77 at P0
    assert len(doc["warnings"]) == 1 and "near a singularity" in doc["warnings"][0]


@pytest.mark.parametrize("argv", [
    ["stiffness", "{d}/haptic_6psu.toml", "--point", "P3"],
    # --check: an analytical-only run without it evaluates no check, which is not a PASS (exit 1)
    ["verify", "{d}/haptic_6psu.toml", "--level", "none", "--check", "--baseline", "{b}", "--out", "{d}/run_ok"],
    ["verify", "{d}/haptic_6psu.toml", "--level", "none", "--check", "--baseline", "{b}", "--out", "{d}/run_ok"],   # a rerun empties its own folder
], ids=["stiffness", "verify", "verify_again"])
def test_good_input_exits_0(inputs, capsys, argv):
    baseline = Path(__file__).resolve().parents[1] / "reports" / "baseline" / "analytical.json"
    assert main([a.format(d=inputs, b=baseline) for a in argv]) == 0
    assert "Traceback" not in "".join(capsys.readouterr())
