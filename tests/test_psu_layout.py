"""The 6-PSU reference case is a parallel_device written leg by leg: its layout tables are read back from the legs,
a variant of a table writes the legs again, and the analytical baseline holds."""
from __future__ import annotations

import json

import numpy as np
import pytest

import femcheck
from femcheck.case.psu_layout import TABLES, _table, layout_legs, psu_layout
from tests.conftest import REFERENCE_CASE, ROOT

#: the issue's bar for the analytical baseline; the case's numbers move only by rounding of the points (measured 7e-15)
BASELINE_RTOL = 1e-12


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case(REFERENCE_CASE)


def test_reference_case_is_a_parallel_device_with_the_6psu_layout(case):
    assert case.meta.kind == "parallel_device" and case.kind == "haptic_6psu"
    g = case.geometry
    # the paper's layout as chosen for the reference (docs/conventions.md §2), read back from the legs
    assert (g.base_radius_m, g.base_pair_half_angle_deg, g.platform_radius_m, g.platform_pair_half_angle_deg,
            g.proximal_link_length_m, g.rail_length_m, g.min_slider_position_m) == (0.18, 17.0, 0.09, 24.0, 0.18, 0.32, 0.05)
    assert case.actuation.cable_modulus_Pa == 90e9 and case.actuation.fe.model == "elements"
    assert case.loads.detailed_test_N == 15.0 and case.loads.simplified_preload_N == 15.0
    assert case.measurement.trials == 3


def test_legs_written_from_the_tables_are_the_file(case):
    lay = psu_layout(case)
    legs, home = layout_legs({t: _table(getattr(lay, t)) for t in TABLES}, case.workspace.nominal_tcp_m, (0, 0, 0))
    pts = lambda k: np.array([leg["joints"][k]["point_m"] for leg in legs])
    for k in (0, 2, 3):
        assert np.abs(pts(k) - [leg.joints[k].point_m for leg in case.legs]).max() < 1e-15  # rounding only
    assert np.allclose(home, case.platform.home_pose, rtol=0, atol=1e-15)


def test_analytical_baseline_within_1e_12(case):
    from femcheck.verify.analytical import run_analytical
    from femcheck.verify.compute import baseline_values
    base = json.loads((ROOT / "reports" / "baseline" / "analytical.json").read_text())
    now = baseline_values(run_analytical(case))
    assert set(now) == set(base)
    worst = max(abs(now[k] - base[k]) / abs(base[k]) for k in base)
    assert worst < BASELINE_RTOL, worst


def test_a_table_variant_writes_the_legs_again(case):
    v = case.with_params(**{"geometry.base_radius_m": 0.19, "guideway.width_radial_m": 0.016,
                            "actuation.cable_modulus_Pa": 80e9})
    assert v.kind == "haptic_6psu" and v.geometry.base_radius_m == 0.19
    assert np.allclose(np.hypot(*v.base_points[:, :2].T), 0.19, rtol=1e-15)
    assert {leg.links[0].width_m for leg in v.legs} == {0.016}
    assert {leg.joints[1].drive.cable_modulus_Pa for leg in v.legs} == {80e9}
    # every leg still closes at the home pose: |C - B| = L2 and B on its rail above A
    B = np.array([leg.joints[2].point_m for leg in v.legs])
    C = np.array([leg.joints[3].point_m for leg in v.legs])
    assert np.allclose(np.linalg.norm(C - B, axis=1), 0.18, rtol=1e-14)
    assert case.geometry.base_radius_m == 0.18       # the original is unchanged
    with pytest.raises(femcheck.errors.CaseError, match="geometry.base_radius_m"):
        case.with_params(**{"geometry.base_radius_m": -0.1})


def test_a_leg_off_the_pattern_is_a_general_parallel_device(case):
    """One leg's clamp moved: no 6-PSU layout, the case runs as a general parallel device (no tables)."""
    A = list(case.legs[0].joints[0].point_m)
    B = list(case.legs[0].joints[2].point_m)
    A[0] += 0.002
    B[0] += 0.002
    v = case.with_params(**{"legs.0.joints.0.point_m": A, "legs.0.joints.2.point_m": B})
    assert v.kind == "parallel_device" and v.layout is None
    with pytest.raises(AttributeError, match="6-PSU layout"):
        v.geometry
