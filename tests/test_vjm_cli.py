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
    out = json.loads(_run("cases/irb120.toml", "--pose", "0,45,-45,-45,45,0", "--wrench", "29.43,0,0,0,0,0", "--json", "-").stdout)
    assert len(out["deflection"]) == 6 and np.asarray(out["K"]).shape == (6, 6)
    d, K = np.asarray(out["deflection"]), np.asarray(out["K"])
    # K is the stiffness of the same model: K d = F (posture 2 of seed 003 Table 6 is regular), round-off of a 6x6 inverse
    np.testing.assert_allclose(K @ d, [29.43, 0, 0, 0, 0, 0], atol=1e-6)
    assert out["complementary_stiffness"] is True and out["rank"] == 6
    assert 1e-6 < np.linalg.norm(d[:3]) < 1e-3                 # SI metres: tens of micrometres here


def test_json_no_complementary_and_extended():
    a = json.loads(_run("cases/cobot7.toml", "--pose", "0,30,0,-90,0,60,0", "--wrench", "10,0,0,0,0,0", "--json", "-").stdout)
    b = json.loads(_run("cases/cobot7.toml", "--pose", "0,30,0,-90,0,60,0", "--wrench", "10,0,0,0,0,0", "--json", "-",
                        "--vjm", "conventional", "--no-complementary").stdout)
    assert a["vjm"] == "extended" and b["vjm"] == "conventional" and not b["complementary_stiffness"]
    # the tilt springs add compliance: the extended model deflects more
    assert np.linalg.norm(a["deflection"][:3]) > np.linalg.norm(b["deflection"][:3])


def test_json_parallel_pose_and_test_point_agree():
    a = json.loads(_run("cases/hiss.toml", "--pose", "TP3", "--wrench", "0,0,-10,0,0,0", "--json", "-").stdout)
    x = ",".join(f"{v:.12f}" for v in a["pose"])
    b = json.loads(_run("cases/hiss.toml", "--pose", x, "--wrench", "0,0,-10,0,0,0", "--json", "-").stdout)
    # TP3 by name and by its platform point in mm are the same pose (12-decimal mm string)
    np.testing.assert_allclose(a["deflection"], b["deflection"], rtol=1e-9)
    assert np.asarray(a["K"]).shape == (6, 6) and a["pose_unit"].startswith("mm")


def test_table_output_and_errors(capsys):
    res = _run("cases/irb120.toml", "--pose", "0,0,0,0,0,0", "--wrench", "0,0,-29.43,0,0,0")
    assert "dz" in res.stdout and "um" in res.stdout and "mrad" in res.stdout and "singular posture" in res.stdout
    assert main(["deflect", "cases/irb120.toml", "--pose", "0,0,0", "--wrench", "0,0,1,0,0,0"]) == 2
    assert "got 3 values; expected 6" in capsys.readouterr().err
    assert main(["deflect", "cases/hiss.toml", "--pose", "172,172,300", "--wrench", "0,0,1,0,0,0"]) == 2
    assert "unreachable" in capsys.readouterr().err
