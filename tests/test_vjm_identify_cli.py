"""``femcheck identify`` on data made by the case's own extended model (seed 002 eqs. 9-12)."""
import csv
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from femcheck.case import load_case
from femcheck.cli import get_app, main
from femcheck.vjm.serial_vjm import deflect

KEYS = {"model", "compliances", "compliances_ci", "cond_A", "kappa_inv", "torsion_share",
        "error_identification_pct", "error_verification_pct"}


@pytest.fixture(scope="module")
def data_csv(tmp_path_factory):
    case = load_case("cases/cobot7.toml")
    model = case.vjm()
    p = case.identification
    rng = np.random.default_rng(21)
    qid = np.array(p.configurations_deg, dtype=float)
    # verification: seed 002 Table I configurations 9-13 from the case, plus 3 random poses (own choice, seeded)
    qver = np.vstack([np.array(p.verification_configurations_deg), rng.uniform(-90, 90, (3, case.n_joints))])
    qdeg = np.vstack([np.repeat(qid, len(p.wrenches), 0), np.repeat(qver, len(p.wrenches), 0)])
    W = np.tile(np.array(p.wrenches), (len(qid) + len(qver), 1))
    dX = deflect(model, np.deg2rad(qdeg), W, complementary=False).twist[:, :3]
    path = tmp_path_factory.mktemp("id") / "data.csv"
    n = case.n_joints
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["set"] + [f"q{j + 1}" for j in range(n)] + ["fx", "fy", "fz", "mx", "my", "mz", "dx", "dy", "dz"])
        for i in range(len(qdeg)):
            w.writerow(["identification" if i < len(qid) * len(p.wrenches) else "verification",
                        *qdeg[i], *W[i], *dX[i]])
    return path, 1.0 / np.array(model.k_theta)


def _run(*args):
    r = CliRunner().invoke(get_app(), ["identify", *map(str, args)])
    return r


def test_extended_identify_recovers_the_model_that_made_the_data(data_csv, tmp_path):
    path, c_true = data_csv
    out = tmp_path / "id.json"
    r = _run("cases/cobot7.toml", path, "--model", "extended", "--json", out)
    assert r.exit_code == 0, r.output
    res = json.loads(out.read_text())
    assert set(res) == KEYS
    # noise-free data from the same model: only round-off amplified by cond(A) remains
    np.testing.assert_allclose(res["compliances"], c_true, rtol=1e-6)
    assert res["error_identification_pct"]["max"] < 1e-6 and res["error_verification_pct"]["max"] < 1e-6
    assert len(res["kappa_inv"]) == 16 and all(0 < x <= 1 for x in res["kappa_inv"])


def test_conventional_model_cannot_explain_extended_data(data_csv):
    path, _ = data_csv
    r = _run("cases/cobot7.toml", path, "--model", "conventional", "--json", "-")
    assert r.exit_code == 0, r.output
    res = json.loads(r.output)
    assert res["torsion_share"] == pytest.approx(1.0)        # torsion springs are all the conventional model has
    # the tilt springs carry ~27 % of the deflection; a torsion-only fit must leave a visible error
    assert res["error_verification_pct"]["mean"] > 1.0


def test_bad_csv_is_a_one_line_error(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("set,q1\nidentification,0\n")
    assert main(["identify", "cases/cobot7.toml", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "expected header columns" in err and len(err.strip().splitlines()) == 1


def test_make_data_round_trips_and_never_overwrites(tmp_path, capsys):
    path = tmp_path / "d.csv"
    assert main(["identify", "cases/cobot7.toml", str(path), "--make-data"]) == 0
    assert len(path.read_text().splitlines()) == 1 + 26            # seed 002: 13 configurations x 2 wrenches
    r = _run("cases/cobot7.toml", path, "--json", "-")
    res = json.loads(r.output)
    c_true = 1.0 / np.array(load_case("cases/cobot7.toml").vjm().k_theta)
    np.testing.assert_allclose(res["compliances"], c_true, rtol=1e-6)  # noise-free, round-off x cond(A)
    assert main(["identify", "cases/cobot7.toml", str(path), "--make-data"]) == 2
    assert "never overwrites" in capsys.readouterr().err
