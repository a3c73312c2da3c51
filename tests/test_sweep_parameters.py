"""Sweep parameters and designs: parsing, validation against the case (errors name the key), designs."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import femcheck
from femcheck.cli import get_app
from femcheck.errors import CaseError
from femcheck.sweep.design import make_design
from femcheck.sweep.parameters import parse_param, parse_params

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "haptic_6psu.toml"


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case(CASE)


def test_parse_forms():
    r = parse_param("guideway.width_radial_m=0.010:0.020")
    assert (r.key, r.lo, r.hi, r.levels, r.log) == ("guideway.width_radial_m", 0.010, 0.020, None, False)
    assert parse_param("a.b=1:2:7").levels == 7
    assert parse_param("a.b=1:2:log").log
    r = parse_param("a.b=1e9:1e11:4:log")
    assert r.levels == 4 and r.log
    # log grid: geometric levels; 1e-12 relative = float rounding of exp/log
    np.testing.assert_allclose(r.grid(3), [1e9, 1e10, 1e11], rtol=1e-12)


@pytest.mark.parametrize("text, fragment", [
    ("guideway.width_radial_m", "expected KEY=LO:HI"),
    ("guideway.width_radial_m=0.02:0.01", "LO = 0.02 must be smaller than HI = 0.01"),
    ("guideway.width_radial_m=0.01:0.01", "must be smaller"),
    ("guideway.width_radial_m=a:0.02", "must be numbers"),
    ("guideway.width_radial_m=0.01:0.02:x", "level count N or 'log'"),
    ("guideway.width_radial_m=0.01:0.02:0", "expected >= 1"),
    ("seat.curv=-1:1:log", "a log range needs LO > 0"),
])
def test_syntax_errors_name_the_key(text, fragment):
    with pytest.raises(CaseError, match=fragment) as info:
        parse_param(text)
    key = text.partition("=")[0]
    assert key in str(info.value)


@pytest.mark.parametrize("text, fragment", [
    ("guideway.width_radial_mm=0.01:0.02", "unknown key"),
    ("guidway.width_radial_m=0.01:0.02", "no section [guidway]"),
    ("materials.titanium.E_Pa=1e11:2e11", "material 'titanium' is not defined"),
    ("measurement.trials=1:5", "not a continuous quantity"),
    ("guideway.material=1:2", "not a continuous quantity"),
    ("guideway.width_radial_m=-0.01:0.02", "range end LO = -0.01 m is invalid"),
    ("proximal_link.inner_diameter_m=0.004:0.007", "range end HI = 0.007 m is invalid"),
    ("materials.steel.nu=0.2:0.6", "range end HI = 0.6"),
])
def test_case_errors_name_the_key_and_value(case, text, fragment):
    with pytest.raises(CaseError, match=fragment.replace("[", r"\[").replace("]", r"\]")) as info:
        parse_params(case, [text])
    assert text.partition("=")[0] in str(info.value)


def test_corner_of_the_box_is_checked(case):
    # each range alone is valid, but inner 5.5 mm > outer 5.2 mm at one corner
    with pytest.raises(CaseError, match="corner .* is invalid") as info:
        parse_params(case, ["proximal_link.outer_diameter_m=0.0052:0.008", "proximal_link.inner_diameter_m=0.004:0.0055"])
    assert "inner_diameter_m" in str(info.value)


def test_duplicate_key(case):
    with pytest.raises(CaseError, match="given twice"):
        parse_params(case, ["guideway.width_radial_m=0.01:0.02", "guideway.width_radial_m=0.01:0.03"])


def test_kinds(case):
    rs = parse_params(case, ["guideway.width_radial_m=0.01:0.02", "materials.aluminium.E_Pa=6e10:8e10",
                             "geometry.base_radius_m=0.17:0.19", "materials.steel.density_kg_m3=7000:8000"])
    assert [r.kind for r in rs] == ["array", "array", "variant", "variant"]
    assert rs[0].nominal == 0.014 and rs[0].unit == "m"


def test_cli_invalid_key_exits_2_naming_it():
    from femcheck.cli import main
    rc = main(["sweep", str(CASE), "--param", "guideway.widht_radial_m=0.01:0.02", "--out", "/nonexistent/x"])
    assert rc == 2
    res = CliRunner().invoke(get_app(), ["sweep", str(CASE), "--param", "guideway.width_radial_m=0.03:0.02"])
    assert isinstance(res.exception, CaseError)
    assert "guideway.width_radial_m" in str(res.exception)


def test_designs_reproducible_and_in_range(case):
    rs = parse_params(case, ["guideway.width_radial_m=0.01:0.02", "materials.aluminium.E_Pa=6e10:8e10:log"])
    for kind in ("lhs", "sobol"):
        a, b = make_design(rs, kind, 32, seed=7), make_design(rs, kind, 32, seed=7)
        np.testing.assert_array_equal(a.values, b.values)
        assert not np.array_equal(a.values, make_design(rs, kind, 32, seed=8).values)
        assert np.all(a.values[:, 0] >= 0.01) and np.all(a.values[:, 0] <= 0.02)
        assert np.all(a.values[:, 1] >= 6e10) and np.all(a.values[:, 1] <= 8e10)
    lhs = make_design(rs, "lhs", 40, seed=1)
    # Latin hypercube: exactly one sample in each of the 40 equal strata of every (unit-scaled) axis
    u0 = (lhs.values[:, 0] - 0.01) / 0.01
    u1 = np.log(lhs.values[:, 1] / 6e10) / np.log(8 / 6)
    for u in (u0, u1):
        assert sorted(np.floor(u * 40).astype(int).clip(0, 39)) == list(range(40))
    sob = make_design(rs, "sobol", 20, seed=0)  # rounded up to 32 base samples
    assert sob.n_base == 32 and sob.m == 32 * 4
    A, B = sob.values[sob.block == 0], sob.values[sob.block == 1]
    AB0 = sob.values[sob.block == 2]
    np.testing.assert_array_equal(AB0[:, 0], B[:, 0])  # AB_i = A with column i from B (Saltelli)
    np.testing.assert_array_equal(AB0[:, 1], A[:, 1])
    grid = make_design(rs, "grid", 3)
    assert grid.m == 9 and grid.levels == (3, 3)
