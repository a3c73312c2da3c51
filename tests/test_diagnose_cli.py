"""``femcheck diagnose`` end to end: JSON fields, report files, input untouched, bad input -> exit 2."""
import hashlib
import json

import pytest

from femcheck.cli import main


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    d = tmp_path_factory.mktemp("diag")
    csv = d / "m.csv"
    assert main(["experiment", "simulate", "cases/haptic_6psu.toml", "--effect", "actuation_compliance:scale=2.5",
                 "--seed", "2", "--directions", "+x,+y,+z", "--out", str(csv), "--truth", str(d / "t.json")]) == 0
    return d, csv


def test_diagnose_json_and_report(data, capsys, monkeypatch):
    d, csv = data
    # a warning that names a TOML table: console markup must print it, not swallow "[measurement]" as a style tag
    import femcheck.diagnose.device_match as device_match
    monkeypatch.setattr(device_match, "device_mismatch_warnings",
                        lambda *a: ["dial step differs from [measurement] dial_resolution_m"])
    digest = hashlib.sha256(csv.read_bytes()).hexdigest()
    out, rep = d / "out.json", d / "report"
    assert main(["diagnose", "cases/haptic_6psu.toml", str(csv), "--model", "detailed", "--json", str(out),
                 "--report", str(rep)]) == 0
    j = json.loads(out.read_text())
    assert [c["id"] for c in j["causes"]] == ["actuation_compliance"] and j["significant"] is True
    c = j["causes"][0]
    assert set(c) == {"id", "probability", "location", "params", "params_ci", "on_bound", "heldout_loss_pct"}
    # one cause: leaving it out costs what it gained, the held-out error of the model as given minus the extended's
    assert j["rank_by"] == "heldout_loss"
    assert c["heldout_loss_pct"] == pytest.approx(100 * (j["heldout_error_before"]["overall"]
                                                         - j["heldout_error_after"]["overall"]), rel=1e-9)
    assert j["residual"]["sigma_estimated"] is True and "spread of the repeated trials" in j["residual"]["sigma_source"]
    assert j["verdict"] == "explained" and 0.5 < c["probability"] <= 1.0
    assert set(j["residual"]) >= {"chi2_per_dof", "p_value", "sigma_m", "unexplained_fraction"}
    assert c["params_ci"]["scale"][0] < 2.5 < c["params_ci"]["scale"][1]
    for key in ("heldout_error_before", "heldout_error_after"):
        assert set(j[key]) == {"x", "y", "z", "overall"}
    assert set(j["heldout_error_by_direction_before"]) == {"+x", "+y", "+z"}
    assert j["heldout_error_after"]["overall"] < 0.5 * j["heldout_error_before"]["overall"]
    html = (rep / "report.html").read_text()
    assert "data:image/png;base64," in html and "<img" in html and 'src="residual_map.png"' not in html
    md = (rep / "report.md").read_text()
    assert "| Rel. error % | P0 |" in md and (rep / "residual_map.png").stat().st_size > 1000
    assert hashlib.sha256(csv.read_bytes()).hexdigest() == digest     # input never modified
    out = capsys.readouterr().out
    assert "actuation_compliance" in out
    assert "dial step differs from [measurement] dial_resolution_m" in " ".join(out.split())


def test_diagnose_bad_csv_names_row_and_column(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("point,direction,trial,phase,load_N,fx_N,fy_N,fz_N,dx_mm,dy_mm,dz_mm\nP0,+x,1,preload,5,5,0,0,x,0,0\n")
    assert main(["diagnose", "cases/haptic_6psu.toml", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "row 2" in err and "dx_mm" in err


def test_diagnose_refuses_to_write_over_its_input(data, capsys):
    _, csv = data
    assert main(["diagnose", "cases/haptic_6psu.toml", str(csv), "--json", str(csv)]) == 2
    assert "input file" in capsys.readouterr().err


@pytest.mark.slow   # a second full diagnosis for the stdout path (CI budget); the JSON keys: test_diagnose_json_and_report
def test_diagnose_json_to_stdout(data, capsys):
    d, csv = data
    assert main(["diagnose", "cases/haptic_6psu.toml", str(csv), "--json", "-"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["verdict"] in ("none", "explained", "unexplained") and "residual" in j


@pytest.mark.parametrize("extra, culprit", [
    (["--report", "cases/haptic_6psu.toml"], "--report"),            # an existing file, not a folder
    (["--json", "cases/haptic_6psu.toml/out.json"], "--json"),        # its folder is a file (missing folders are created)
    (["--json", "cases"], "--json"),                                    # a folder, not a file
])
def test_diagnose_bad_output_paths_exit_2_before_work(data, capsys, extra, culprit):
    d, csv = data
    assert main(["diagnose", "cases/haptic_6psu.toml", str(csv), *extra]) == 2
    err = capsys.readouterr().err
    assert culprit in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("kind_case, says", [("cases/irb120.toml", "mass_kg"), ("cases/hiss.toml", "haptic_6psu")])
def test_diagnose_wrong_case_kind_names_the_kinds_it_takes(data, capsys, kind_case, says):
    """A parallel_vjm case is not diagnosable (the kinds taken are named); a serial robot loads through the tree
    and is refused for its missing link masses."""
    d, csv = data
    assert main(["diagnose", kind_case, str(csv)]) == 2
    err = capsys.readouterr().err
    assert says in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_simulate_unwritable_output_exit_2(tmp_path, capsys):
    assert main(["experiment", "simulate", "cases/haptic_6psu.toml", "--out", "cases/haptic_6psu.toml/m.csv",
                 "--truth", str(tmp_path / "t.json")]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and "Traceback" not in err and not (tmp_path / "t.json").exists()
