"""Sweep results and analysis against closed forms, the reference numbers and invariants."""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import femcheck
from femcheck.chain import evaluate
from femcheck.cli import get_app
from femcheck.sweep.analysis import analyse, local_elasticities, log_log_slopes, pareto_front
from femcheck.sweep.evaluate_analytical import element_mass_kg
from femcheck.sweep.parameters import parse_params
from femcheck.sweep.run import run_sweep

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "haptic_6psu.toml"


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case(CASE)


def _col(t, name):
    return np.asarray(t.column(name).to_numpy(zero_copy_only=False))


def test_nominal_sample_reproduces_reference_and_direct_model(case, tmp_path):
    rs = parse_params(case, ["guideway.width_radial_m=0.010:0.018:3"])  # middle level = nominal 14 mm
    out = run_sweep(case, rs, tmp_path, design="grid", jobs=0)
    t = out.table
    row = np.flatnonzero((_col(t, "sample_id") == 1) & (_col(t, "point") == "P0"))[0]
    assert _col(t, "p:guideway.width_radial_m")[row] == pytest.approx(0.014, rel=1e-15)  # linspace rounding
    # CONVENTIONS / case file reference: detailed, rigid joints, 15 N: P0 deflection 0.2662 mm (x), 0.0661 mm (z);
    # quoted to 4 significant digits -> 2e-4 relative (z: 0.0661 to 3 digits -> 1e-3)
    np.testing.assert_allclose(_col(t, "defl_x_m")[row], 0.2662e-3, rtol=2e-4)
    np.testing.assert_allclose(_col(t, "defl_z_m")[row], 0.0661e-3, rtol=1e-3)
    # the same model called directly: only float rounding may differ (1e-12 relative)
    direct = evaluate(case, femcheck.test_points(case), [0, 15.0, 0, 0, 0, 0])
    rows = np.flatnonzero(_col(t, "sample_id") == 1)
    np.testing.assert_allclose(_col(t, "k_y_N_per_m")[rows], 15.0 / direct.twist[:, 1], rtol=1e-12)


def test_array_and_variant_paths_agree(case, tmp_path):
    rs = parse_params(case, ["guideway.width_radial_m=0.010:0.020", "universal_joint.pin_radius_m=0.0008:0.0014"])
    a = run_sweep(case, rs, tmp_path / "a", design="lhs", samples=12, jobs=0, points=("P0", "P6"))
    forced = [dataclasses.replace(r, kind="variant") for r in rs]  # case.with_params per sample instead of arrays
    b = run_sweep(case, forced, tmp_path / "b", design="lhs", samples=12, jobs=0, points=("P0", "P6"))
    for c in ("k_x_N_per_m", "k_y_N_per_m", "k_z_N_per_m", "share_guideway", "share_universal_joint", "mass_kg"):
        # same physics, parameters packed from arrays vs from a rebuilt case: float rounding only (1e-12)
        np.testing.assert_allclose(_col(a.table, c), _col(b.table, c), rtol=1e-12, err_msg=c)


def test_simplified_stiffness_is_proportional_to_link_modulus(case, tmp_path):
    """Simplified model = guideways + links, both aluminium: every compliance is 1/E (G = E/(2(1+nu)))
    so k ∝ E_al and d ln k / d ln E_al = 1 exactly."""
    rs = parse_params(case, ["materials.aluminium.E_Pa=5e10:9e10"])
    out = run_sweep(case, rs, tmp_path, design="lhs", samples=16, model="simplified", jobs=0, points=("P0", "P2"))
    an = analyse(out)
    for name, e in an.elasticity.items():
        # an exact power law: least squares recovers the exponent to float rounding (1e-9)
        assert abs(e[0] - 1.0) < 1e-9, name
        assert an.elasticity_r2[name] == pytest.approx(1.0, abs=1e-9)
    # local, with a second (non-power-law) parameter present: the E derivative is still exactly 1
    rs = parse_params(case, ["materials.aluminium.E_Pa=5e10:9e10", "guideway.width_radial_m=0.012:0.016"])
    local = local_elasticities(case, rs, model="simplified", points=("P0", "P2"))
    for name, e in local.items():
        # central difference of an exactly ln-linear function: rounding only, ~1e-13 / 2e-3 (1e-8)
        assert abs(e[0] - 1.0) < 1e-8, name


def test_guideway_width_elasticity_matches_beam_theory(case):
    """k along x vs guideway width b (simplified model, linear).

    d ln k / d ln b = sum over guideway energy terms of (exponent x share): radial bending ∝ b^-3
    (I_y = h b^3 / 12), tangential bending and axial ∝ b^-1, torsion between (J_t, b > h), links
    unaffected. So it must be positive and lie between 1 and 3 times the guideway energy share.
    """
    rs = parse_params(case, ["guideway.width_radial_m=0.010:0.020"])
    e = local_elasticities(case, rs, model="simplified", joints="rigid")["+x"][0]
    P = femcheck.test_points(case)
    r = evaluate(case, P, [case.loads.simplified_test_N, 0, 0, 0, 0, 0], model="simplified", joints="rigid")
    j = np.argmin(1.0 / r.twist[:, 0])
    share = r.contributions[j, 0]
    # bounds are exact for the linear model; 1e-5 covers the O(h^2) = 1e-6 central-difference truncation
    assert share - 1e-5 <= e <= 3 * share + 1e-5, (e, share)
    # the reference device's guideways load mostly in radial bending: e is nearer the b^-3 bound
    assert e > 2.0 * share


def test_non_influential_parameter_has_zero_sobol_indices(case, tmp_path):
    """Steel density does not enter the stiffness: f(AB_i) = f(A) exactly, so the Saltelli first-order
    and Jansen total estimators are exactly 0 for it; it does change the mass."""
    rs = parse_params(case, ["guideway.width_radial_m=0.010:0.020", "materials.steel.density_kg_m3=7000:9000"])
    out = run_sweep(case, rs, tmp_path, design="sobol", samples=16, model="detailed", jobs=0, points=("P0", "P5"))
    an = analyse(out)
    for name in an.sobol_first:
        assert abs(an.sobol_first[name][1]) < 1e-12 and abs(an.sobol_total[name][1]) < 1e-12, name
        # all the variance comes from the width; the estimators' sampling error at n = 16 is O(n^-1/2) ~ 0.25
        assert an.sobol_total[name][0] > 0.5 and an.sobol_first[name][0] > 0.5
    assert np.ptp(an.mass_kg) > 0


def test_grid_main_effect_of_single_parameter_is_one(case, tmp_path):
    rs = parse_params(case, ["proximal_link.outer_diameter_m=0.006:0.009:4"])
    an = analyse(run_sweep(case, rs, tmp_path, design="grid", jobs=0, points=("P0",)))
    for name, s in an.sobol_first.items():
        assert s[0] == pytest.approx(1.0, abs=1e-12)  # Var(E[Y|x]) = Var(Y) when x is the only input


def test_unreachable_samples_are_marked_not_ok(case, tmp_path):
    """Slider positions at the cube are 162-260 mm (case file); a rail shorter than that makes points
    unreachable: those samples are kept as NaN with ok = False, the others are evaluated."""
    rs = parse_params(case, ["geometry.rail_length_m=0.20:0.32:4", "guideway.width_radial_m=0.01:0.02:2"])
    out = run_sweep(case, rs, tmp_path, design="grid", jobs=0)
    an = analyse(out)
    rail = an.params[:, 0]
    np.testing.assert_array_equal(an.ok, rail > 0.27)  # levels 0.20, 0.24 fail; 0.28, 0.32 reach all points
    assert np.all(np.isnan(an.k_min["+x"][~an.ok])) and np.all(np.isfinite(an.k_min["+x"][an.ok]))
    # the rail length only limits reach, it does not enter any compliance: zero elasticity (rounding, 1e-9)
    assert abs(an.elasticity["+x"][0]) < 1e-9
    assert an.sobol_first is None and "failed" in an.sobol_method


def test_mass_closed_form(case):
    # 6 x (guideway bar 14x10 mm x 320 mm Al + tube 6/5 mm x 180 mm Al + ball R 3.5 mm steel + 2 pins r 1 mm x 24 mm steel)
    expected = 6 * (2700 * 0.014 * 0.010 * 0.320 + 2700 * np.pi * (0.006**2 - 0.005**2) / 4 * 0.180
                    + 7850 * 4 / 3 * np.pi * 0.0035**3 + 2 * 7850 * np.pi * 0.001**2 * 0.024)
    assert element_mass_kg(case) == pytest.approx(expected, rel=1e-14)  # same formula, rounding only
    m = element_mass_kg(case, {"guideway.width_radial_m": np.array([0.014, 0.028])})
    assert m[1] - m[0] == pytest.approx(6 * 2700 * 0.014 * 0.010 * 0.320, rel=1e-12)  # linear in b


def test_log_log_slopes_recover_power_law():
    rng = np.random.default_rng(3)
    P = rng.uniform(1, 10, (50, 2))
    k = 7.0 * P[:, 0] ** 2.5 * P[:, 1] ** -0.5
    e, r2 = log_log_slopes(P, k, np.ones(50, bool))
    np.testing.assert_allclose(e, [2.5, -0.5], atol=1e-10)  # exact power law: rounding only
    assert r2 == pytest.approx(1.0, abs=1e-12)


def test_pareto_front_is_non_dominated():
    rng = np.random.default_rng(5)
    mass, k = rng.uniform(0, 1, 200), rng.uniform(0, 1, 200)
    front = pareto_front(mass, k, np.ones(200, bool))
    for i in front:
        assert not np.any((mass < mass[i]) & (k > k[i]))
    dominated = np.setdiff1d(np.arange(200), front)
    for i in dominated:
        assert np.any((mass <= mass[i]) & (k >= k[i]) & ((mass < mass[i]) | (k > k[i])))


def test_cli_writes_store_manifest_and_html(tmp_path):
    out = tmp_path / "sweep"
    res = CliRunner().invoke(get_app(), [
        "sweep", str(CASE), "--param", "guideway.width_radial_m=0.010:0.020",
        "--param", "proximal_link.outer_diameter_m=0.006:0.009:log", "--design", "sobol", "--samples", "8",
        "--points", "P0,P7", "--jobs", "0", "--out", str(out)])
    assert res.exit_code == 0, res.output
    man = json.loads((out / "manifest.json").read_text())
    assert man["status"] == "complete" and man["case"]["sha256"] == femcheck.load_case(CASE).sha256
    assert man["sample_points"] == 8 * 4 * 2
    assert {p["key"] for p in man["parameters"]} == {"guideway.width_radial_m", "proximal_link.outer_diameter_m"}
    import pyarrow.parquet as pq
    assert pq.read_table(out / "results.parquet").num_rows == 64
    html = (out / "summary.html").read_text()
    assert html.count("data:image/png;base64,") == 5 and "Sobol" in html
    an = json.loads((out / "analysis.json").read_text())
    assert an["samples_ok"] == 32 and an["sobol_total"] is not None
    # the same command again without --resume refuses to mix results; with --resume it reuses all samples
    again = CliRunner().invoke(get_app(), ["sweep", str(CASE), "--param", "guideway.width_radial_m=0.010:0.020",
                                           "--param", "proximal_link.outer_diameter_m=0.006:0.009:log", "--design",
                                           "sobol", "--samples", "8", "--points", "P0,P7", "--jobs", "0",
                                           "--out", str(out), "--resume", "--no-report"])
    assert again.exit_code == 0, again.output
    assert "32 samples reused" in " ".join(again.output.split())


def test_single_parameter_sobol_design_reports_indices(tmp_path):
    """Regression: with one parameter scipy returns scalars; the indices must still be one per parameter."""
    from typer.testing import CliRunner
    from femcheck.cli import get_app
    res = CliRunner().invoke(get_app(), ["sweep", "cases/haptic_6psu.toml", "--param", "guideway.width_radial_m=0.010:0.020",
                                         "--design", "sobol", "--samples", "16", "--model", "simplified",
                                         "--out", str(tmp_path / "s"), "--jobs", "0", "--no-report"])
    assert res.exit_code == 0, res.output
    assert "Sobol" in res.output and "guideway.width_radial_m" in res.output
