"""`femcheck stiffness` and `femcheck map` on the two parallel_device reference cases, in-process."""
from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from femcheck.case import load_case
from femcheck.cli import get_app, main
from femcheck.parallel.chain_model import evaluate
from femcheck.parallel.device import test_points as cube_points
from tests.conftest import ROOT

runner = CliRunner()
CASES = [ROOT / "cases" / "hexapod_6ups.toml", ROOT / "cases" / "delta_3ruu.toml"]


@pytest.mark.parametrize("path", CASES)
def test_stiffness_json_matches_the_library(path):
    res = runner.invoke(get_app(), ["stiffness", str(path), "--point", "P5", "--wrench", "0,5,-10,0,0,0", "--json", "-"])
    assert res.exit_code == 0, res.output
    obj = json.loads(res.output)
    case = load_case(path)
    r = evaluate(case.device, cube_points(case)[5], [0, 5, -10, 0, 0, 0], joints=case.model.joint_rotations)
    assert np.allclose(obj["K"], r.K[0], rtol=1e-12)
    assert sum(obj["contributions"].values()) == pytest.approx(1.0, abs=1e-9)
    assert np.allclose(np.array(obj["K"]) @ obj["deflection"], [0, 5, -10, 0, 0, 0], atol=1e-9)


@pytest.mark.parametrize("path", CASES)
def test_stiffness_table_rigid_simplified(path):
    res = runner.invoke(get_app(), ["stiffness", str(path), "--model", "simplified", "--joints", "rigid", "--point", "P7"])
    assert res.exit_code == 0, res.output
    assert "rigid" in res.output and "contributions" in res.output and "N/mm" in res.output


def test_unreachable_pose_is_one_clear_line(capsys):
    assert main(["stiffness", str(CASES[1]), "--pose", "0,0,-0.5,0,0,0"]) == 2
    assert "not reachable by leg" in capsys.readouterr().err


@pytest.mark.parametrize("path", CASES)
def test_map_writes_a_png(path, tmp_path):
    out = tmp_path / "map.png"
    res = runner.invoke(get_app(), ["map", str(path), "--z", "0", "--direction", "y", "--resolution", "15",
                                    "--half-width", "0.05", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert out.read_bytes()[:4] == b"\x89PNG" and "reachable grid points" in res.output


@pytest.mark.parametrize("path, joint_fe", [(CASES[0], False), (CASES[1], False),
                                             pytest.param(CASES[0], True, marks=pytest.mark.slow),
                                             pytest.param(CASES[1], True, marks=pytest.mark.slow)],
                         ids=["hexapod", "delta", "hexapod-joint-fe", "delta-joint-fe"])
def test_verify_writes_tables_and_passes_check(path, joint_fe, tmp_path):
    """verify on a parallel device: the FE with solid links (coarse; P0, where the symmetric legs share one link
    mesh) within 2 % of the analytical model (measured 0.01-0.7 %: shear and the rigid end faces, which the
    Euler-Bernoulli cantilevers leave out; with the joints' contact FE, slow, 0.1-1.8 % at P0, P5), and the FE with
    beam links to round-off (1e-6 %)."""
    out = tmp_path / "run"
    res = runner.invoke(get_app(), ["verify", str(path), "--points", "P0", "--mesh", "coarse", "--out", str(out),
                                    "--check", "--joint-fe" if joint_fe else "--no-joint-fe"])
    assert res.exit_code == 0, res.output
    assert "solid links" in res.output and "beam links" in res.output
    lines = [ln for ln in res.stdout.splitlines() if ln.strip()]
    assert lines[0].startswith("PASS: 13 checks passed") and lines[-1] == lines[0]   # 2 levels x 2 joints x 3 dirs + beam
    verdict = json.loads((out / "verdict.json").read_text())
    assert verdict["passed"] and {c["kind"] for c in verdict["checks"]} == {"threshold"}
    assert "PASS" in (out / "report.html").read_text() and "every point" in (out / "report.md").read_text()
    for name, bound in (("errors_detailed.csv", 2.0), ("errors_simplified.csv", 2.0), ("errors_detailed_beam.csv", 1e-6)):
        rows = (out / name).read_text().splitlines()
        assert rows[0] == "level,joints,point,direction,analytical_mm,fe_mm,rel_error_pct"
        assert len(rows) == 1 + 2 * 1 * 3  # joints x points x directions
        errors = [abs(float(r.split(",")[-1])) for r in rows[1:]]
        assert max(errors) < bound, (name, errors)
        if "beam" not in name:
            assert max(errors) > 1e-6   # the solid links are not the beam formula: a real difference shows


def test_docs_quote_the_real_output():
    """docs/parallel_device.md shows real command output: its quoted lines are what the commands print now."""
    doc = " ".join((ROOT / "docs" / "parallel_device.md").read_text().split())
    for args in (["stiffness", str(CASES[0]), "--point", "P3"], ["stiffness", str(CASES[1]), "--point", "P3", "--joints", "rigid"]):
        res = runner.invoke(get_app(), args)
        assert res.exit_code == 0, res.output
        for line in res.output.splitlines():
            if line.startswith(("deflection:", "directional stiffness", f"{len(load_case(args[1]).device.legs)} legs")):
                assert " ".join(line.split()) in doc, line


def test_stiffness_json_has_per_leg_shares():
    res = runner.invoke(get_app(), ["stiffness", str(CASES[0]), "--point", "P2", "--wrench", "10,0,0,0,0,0", "--json", "-"])
    obj = json.loads(res.output)
    legs = obj["leg_contributions"]
    assert list(legs) == ["a1", "b1", "a2", "b2", "a3", "b3"]
    assert sum(sum(v.values()) for v in legs.values()) == pytest.approx(1.0, abs=1e-9)
    for name, share in obj["contributions"].items():
        assert sum(v.get(name, 0.0) for v in legs.values()) == pytest.approx(share, abs=1e-12)


def test_sweep_of_a_leg_link_and_a_material(tmp_path):
    out = tmp_path / "sweep"
    res = runner.invoke(get_app(), ["sweep", str(CASES[1]), "--param", "legs.0.links.1.outer_diameter_m=0.007:0.010",
                                    "--param", "materials.aluminium.E_Pa=60e9:80e9", "--design", "lhs", "--samples", "8",
                                    "--points", "P0,P7", "--jobs", "0", "--out", str(out), "--no-report"])
    assert res.exit_code == 0, res.output
    import pyarrow.parquet as pq
    table = pq.read_table(out / "results.parquet")
    assert {"share_crank", "share_rod", "share_drive", "share_hertz_line", "k_x_N_per_m"} <= set(table.column_names)
    assert np.asarray(table.column("ok")).all()
    # the local elasticity of k_min to the links' modulus: below 1, since the drives and the steel pins do not
    # scale with it, and close to 1, since the links carry most of the compliance (8 samples are too few for
    # the global fit, so the local central difference is what is checked)
    line = next(ln for ln in res.output.splitlines() if ln.strip("│ ").startswith("all"))
    e_local = float(line.split("│")[3].split("|")[1])
    assert 0.8 < e_local < 1.0


def test_sweep_refuses_fe_for_parallel_devices(tmp_path):
    res = runner.invoke(get_app(), ["sweep", str(CASES[0]), "--param", "materials.aluminium.E_Pa=60e9:80e9",
                                    "--model", "fe", "--out", str(tmp_path / "s")])
    assert res.exit_code == 2 and "not available for parallel_device" in res.output


@pytest.mark.parametrize("path, kind, leg, factor", [(CASES[0], "drive", 3, 2.5), (CASES[1], "rod", 1, 2.0),
                                                     (CASES[1], "crank", None, 1.6)],
                         ids=["hexapod-one-drive", "delta-one-rod", "delta-every-crank"])
def test_diagnose_locates_a_hidden_effect(path, kind, leg, factor, tmp_path):
    """A virtual experiment with one element kind made softer (in one leg, or in all) and 0.2 um dial noise:
    diagnose names the kind and the leg and recovers the factor to 2 % (the noise is ~0.1 % of the deflections)."""
    from femcheck.measured.csv_format import write_measured_csv
    from femcheck.parallel.diagnosis import simulate
    case = load_case(path)
    dev = case.device
    s = np.ones((dev.n_legs, len(dev.element_names)))
    s[slice(None) if leg is None else leg, dev.element_names.index(kind)] = factor
    csv = tmp_path / "measured.csv"
    write_measured_csv(csv, *simulate(case, s, noise_m=2e-7), resolution_m=1e-7)
    res = runner.invoke(get_app(), ["diagnose", str(path), str(csv), "--json", "-"])
    assert res.exit_code == 0, res.output
    obj = json.loads(res.output)
    if leg is None:
        assert obj["best"]["what"] == f"{kind} in every leg" and obj["leg"] is None
        assert obj["effects"][0]["factor"] == pytest.approx(factor, rel=0.02)
    else:
        name = dev.legs[leg].name
        assert obj["best"]["what"] == f"{kind} in legs {name}"
        assert obj["leg"]["name"] == name and obj["leg"]["factor"] == pytest.approx(factor, rel=0.02)
        assert obj["located"]["cause"] == f"{kind}_in_legs" and obj["located"]["legs"] == [name]
        lo, hi = obj["located"]["factor_ci"]
        assert lo < factor < hi
        assert [e["name"] for e in obj["effects"]] == [name]
    assert obj["best"]["held_out_rms_mm"] < 0.02 * obj["best"]["rms_before_mm"]
