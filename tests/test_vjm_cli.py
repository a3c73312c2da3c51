"""``femcheck deflect``: in-process CLI tests (JSON shape, units, errors)."""
import json

import numpy as np
from typer.testing import CliRunner

from femcheck.cli import get_app, main


def _run(*args):
    res = CliRunner().invoke(get_app(), ["deflect", *args])
    assert res.exit_code == 0, (res.output, res.exception)
    return res


def test_json_shape_serial():
    out = json.loads(_run("cases/irb120.toml", "--pose", "0,45,-45,-45,45,0", "--deg", "--wrench", "29.43,0,0,0,0,0", "--json", "-").stdout)
    assert len(out["deflection"]) == 6 and np.asarray(out["K"]).shape == (6, 6)
    d, K = np.asarray(out["deflection"]), np.asarray(out["K"])
    # K is the stiffness of the same model: K d = F (posture 2 of seed 003 Table 6 is regular), round-off of a 6x6 inverse
    np.testing.assert_allclose(K @ d, [29.43, 0, 0, 0, 0, 0], atol=1e-6)
    assert out["complementary_stiffness"] is True and out["rank"] == 6
    assert 1e-6 < np.linalg.norm(d[:3]) < 1e-3                 # SI metres: tens of micrometres here


def test_json_no_complementary_and_extended():
    a = json.loads(_run("cases/cobot7.toml", "--pose", "0,30,0,-90,0,60,0", "--deg", "--wrench", "10,0,0,0,0,0", "--json", "-").stdout)
    b = json.loads(_run("cases/cobot7.toml", "--pose", "0,30,0,-90,0,60,0", "--deg", "--wrench", "10,0,0,0,0,0", "--json", "-",
                        "--vjm", "conventional", "--no-complementary").stdout)
    assert a["vjm"] == "extended" and b["vjm"] == "conventional" and not b["complementary_stiffness"]
    # the tilt springs add compliance: the extended model deflects more
    assert np.linalg.norm(a["deflection"][:3]) > np.linalg.norm(b["deflection"][:3])


def test_json_parallel_pose_and_test_point_agree():
    a = json.loads(_run("cases/hiss.toml", "--pose", "TP3", "--wrench", "0,0,-10,0,0,0", "--json", "-").stdout)
    x = ",".join(f"{v:.12f}" for v in a["pose"])
    b = json.loads(_run("cases/hiss.toml", "--pose", x, "--wrench", "0,0,-10,0,0,0", "--json", "-").stdout)
    # TP3 by name and by its platform point in m are the same pose (12-decimal string: 1e-12 m)
    np.testing.assert_allclose(a["deflection"], b["deflection"], rtol=1e-9)
    assert np.asarray(a["K"]).shape == (6, 6) and a["pose_unit"].startswith("m ")
    c = json.loads(_run("cases/hiss.toml", "--pose", ",".join(f"{1e3 * v:.9f}" for v in a["pose"]), "--mm",
                        "--wrench", "0,0,-10,0,0,0", "--json", "-").stdout)
    np.testing.assert_allclose(c["deflection"], a["deflection"], rtol=1e-9)   # --mm: the same pose in mm


def test_pose_units_are_the_same_in_every_command(capsys):
    """--pose is m and rad everywhere; --deg / --mm state other units; degrees or mm given as SI are refused
    with the option that was meant."""
    q_deg = "0,45,-45,-45,45,0"
    q_rad = ",".join(repr(float(v)) for v in np.deg2rad([0, 45, -45, -45, 45, 0]))
    a = json.loads(_run("cases/irb120.toml", "--pose", q_deg, "--deg", "--wrench", "0,0,-10,0,0,0", "--json", "-").stdout)
    b = json.loads(_run("cases/irb120.toml", "--pose", q_rad, "--wrench", "0,0,-10,0,0,0", "--json", "-").stdout)
    # the same posture in degrees and in radians: the deflection agrees to the round-off of deg2rad
    np.testing.assert_allclose(a["deflection"], b["deflection"], rtol=1e-12)
    # stiffness: the 6-PSU's P0 given in m/rad and in mm/deg gives the same stiffness
    x = [0.0, 0.0, 0.375, 0.0, 0.0, 0.1]
    s1 = json.loads(CliRunner().invoke(get_app(), ["stiffness", "cases/haptic_6psu.toml", "--pose",
                                                    ",".join(map(str, x)), "--json", "-"]).stdout)
    s2 = json.loads(CliRunner().invoke(get_app(), ["stiffness", "cases/haptic_6psu.toml", "--pose",
                                                    f"0,0,375,0,0,{float(np.rad2deg(0.1))!r}", "--mm", "--deg",
                                                    "--json", "-"]).stdout)
    K1 = np.asarray(s1["K"])
    # same pose, unit conversion only: round-off of the largest entry (the zeros are 1e-11 noise)
    np.testing.assert_allclose(s2["K"], K1, rtol=0, atol=1e-9 * np.abs(K1).max())
    # (in-process main() last: it redirects the CLI's output for the rest of the process)
    assert main(["deflect", "cases/irb120.toml", "--pose", q_deg, "--wrench", "0,0,1,0,0,0"]) == 2
    assert "more than a turn" in capsys.readouterr().err   # 45 read as rad: refused, --deg named
    assert main(["stiffness", "cases/haptic_6psu.toml", "--pose", "0,0,375,0,0,0"]) == 2
    assert "give --mm" in capsys.readouterr().err


def test_table_output_and_errors(capsys):
    res = _run("cases/irb120.toml", "--pose", "0,0,0,0,0,0", "--wrench", "0,0,-29.43,0,0,0")
    assert "dz" in res.stdout and "um" in res.stdout and "mrad" in res.stdout and "singular posture" in res.stdout
    assert main(["deflect", "cases/irb120.toml", "--pose", "0,0,0", "--wrench", "0,0,1,0,0,0"]) == 2
    assert "expected 6 comma-separated numbers, got 3" in capsys.readouterr().err
    assert main(["deflect", "cases/hiss.toml", "--pose", "172,172,300", "--mm", "--wrench", "0,0,1,0,0,0"]) == 2
    assert "unreachable" in capsys.readouterr().err
