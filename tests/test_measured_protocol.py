"""Protocol processing (seed 000 eq. 1, §4.3.2 preload identification, uncertainty) on hand-made rows."""
import numpy as np
import pytest

import femcheck
from femcheck.errors import MeasuredDataError
from femcheck.measured import identify_preload, process
from femcheck.measured.csv_format import parse_measured_csv

HEADER = "point,direction,trial,phase,load_N,fx_N,fy_N,fz_N,dx_mm,dy_mm,dz_mm\n"


@pytest.fixture(scope="module")
def case():
    return femcheck.load_case("cases/haptic_6psu.toml")


def test_eq1_delta_and_stiffness_on_hand_made_rows(case):
    rows = ("P0,+x,1,preload,5,5,0,0,0.09,0.01,0\nP0,+x,1,total,20,20,0,0,0.36,0.02,0\n"
            "P0,+x,2,preload,5,5,0,0,0.10,0.00,0\nP0,+x,2,total,20,20,0,0,0.35,0.01,0\n"
            "P0,+x,1,unload,5,5,0,0,0.11,0,0\nP0,+x,1,unload,0,0,0,0,0.01,0,0\n")
    r = process(parse_measured_csv(HEADER + rows), case)
    # eq. 1 per trial: (0.36 - 0.09) and (0.35 - 0.10) mm, averaged -> 0.26 mm; K = 15 N / 0.26 mm
    np.testing.assert_allclose(r.delta[0], [0.26e-3, 0.01e-3, 0.0], rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(r.stiffness(), [15.0 / 0.26e-3], rtol=1e-12)   # float rounding only
    assert (r.preload_N[0], r.test_N[0]) == (5.0, 15.0)
    # unload states remember the peak of their loading sequence (20 N), for the friction model
    assert set(r.peak_N[r.phase == "unload"]) == {20.0}


def test_uncertainty_pools_trial_scatter_and_resolution(case):
    rows = ("P0,+x,1,preload,5,5,0,0,0.09,0,0\nP0,+x,1,total,20,20,0,0,0.36,0,0\n"
            "P0,+x,2,preload,5,5,0,0,0.11,0,0\nP0,+x,2,total,20,20,0,0,0.36,0,0\n")
    r = process(parse_measured_csv(HEADER + rows), case)
    # the readings are whole multiples of 0.01 mm: that is the quantum seen in the data
    assert r.quantum_m == pytest.approx(1e-5, rel=1e-6)   # float gcd tolerance
    # two trials: mean square successive difference over the state axes that read anything (dx of the two states;
    # dy, dz read zero throughout and hide their scatter under the rounding), only the preload's dx moves (0.02 mm):
    # s^2 = (2e-5)^2 / (2 * 2). The noise behind it is about one step, so the rounding error the trials share,
    # b^2 ~ q^2 / (2 pi^2) exp(-4 pi^2), is negligible: sigma_r = s
    assert r.reading_sigma_m == pytest.approx(1e-5, rel=1e-9)   # float rounding
    assert r.sigma_dof == 2
    np.testing.assert_allclose(r.delta_sigma[0], np.sqrt(2) * r.reading_sigma_m / np.sqrt(2), rtol=1e-9)


def test_rounding_error_shared_by_the_trials_does_not_average_down(case):
    """Readings that repeat exactly share their rounding error: the mean of three trials is as uncertain as one
    reading (q / sqrt(12)), not q / sqrt(12 * 3); the axes that read zero throughout keep the (zero) scatter only."""
    rows = "".join(f"P0,+x,{t},preload,5,5,0,0,0.091,0,0\nP0,+x,{t},total,20,20,0,0,0.356,0,0\n" for t in (1, 2, 3))
    r = process(parse_measured_csv(HEADER + rows), case)
    np.testing.assert_allclose(r.sigma[:, 0], 1e-6 / np.sqrt(12), rtol=1e-9)   # b^2(0, q) = q^2 / 12, series to 1e-12


def test_quantization_bias_matches_a_direct_average():
    """b^2(sigma, q) of the Fourier series against a direct average over the offset in the step and the noise."""
    from scipy.stats import norm

    from femcheck.measured.protocol import noise_sigma_from_scatter, quantization_bias_var
    q, u, k = 1.0, np.linspace(0.0, 1.0, 4001)[:-1], np.arange(-30, 31)
    for s in (0.1, 0.2, 0.3, 0.5):
        p = norm.cdf((k[:, None] + 0.5 - u) / s) - norm.cdf((k[:, None] - 0.5 - u) / s)   # P(Q = k | u)
        mean, second = (k[:, None] * p).sum(0), (k[:, None] ** 2 * p).sum(0)
        b2, scatter = np.mean((mean - u) ** 2), np.mean(second - mean ** 2)
        assert quantization_bias_var(s, q) == pytest.approx(b2, rel=1e-6, abs=1e-12)   # 4000-point offset grid
        assert noise_sigma_from_scatter(scatter, q) == pytest.approx(s, rel=1e-5)   # bisection of the same relation


def test_quantum_seen_in_the_data_sets_the_floor(case):
    """Readings that repeat exactly leave only the quantization: sigma = q / sqrt(12), q from the data (1 um),
    not the case's 10 um dial."""
    rows = "".join(f"P0,+x,{t},preload,5,5,0,0,0.091,0,0\nP0,+x,{t},total,20,20,0,0,0.356,0,0\n" for t in (1, 2, 3))
    r = process(parse_measured_csv(HEADER + rows), case)
    assert r.quantum_m == pytest.approx(1e-6, rel=1e-6)   # float gcd tolerance
    assert r.reading_sigma_m == pytest.approx(1e-6 / np.sqrt(12), rel=1e-9) and r.sigma_dof == 0


def test_trial_drift_is_a_finding_not_noise(case):
    """A reading creeping 0.02 mm per trial: the detrended scatter stays at the quantization floor and the
    drift (m / trial) is reported with a large z."""
    rows = "".join(f"P0,+x,{t},preload,5,5,0,0,{0.09 + 0.02 * t:.2f},0,0\nP0,+x,{t},total,20,20,0,0,"
                   f"{0.36 + 0.02 * t:.2f},0,0\nP1,+x,{t},preload,5,5,0,0,{0.08 + 0.02 * t:.2f},0,0\n"
                   f"P1,+x,{t},total,20,20,0,0,{0.30 + 0.02 * t:.2f},0,0\n" for t in (1, 2, 3, 4))
    r = process(parse_measured_csv(HEADER + rows), case)
    assert r.reading_sigma_m == pytest.approx(1e-5 / np.sqrt(12), rel=1e-6)   # exact line: only the floor remains
    assert r.trial_drift_m == pytest.approx(2e-5, rel=1e-6)   # 0.02 mm per trial, float rounding
    assert r.trial_drift_m / r.trial_drift_sigma_m > 5


def test_missing_total_names_row_and_column(case):
    with pytest.raises(MeasuredDataError) as ei:
        process(parse_measured_csv(HEADER + "P0,+x,1,preload,5,5,0,0,0.09,0,0\n", "m.csv"), case)
    assert ei.value.column == "phase" and ei.value.row == 2 and "no total" in str(ei.value)


def test_unknown_pose_id_names_the_row(case):
    with pytest.raises(MeasuredDataError) as ei:
        process(parse_measured_csv(HEADER + "Q7,+x,1,preload,5,5,0,0,0.09,0,0\n", "m.csv"), case)
    assert (ei.value.row, ei.value.column) == (2, "point") and "P0..P8" in str(ei.value)


def test_preload_identification_finds_where_the_dead_band_is_closed(case):
    # staircase 5..30 N with a dead band g closed by the load: delta = g (1 - exp(-F/Fc)) + F / k
    k, g, Fc = 60e3, 40e-6, 2.0
    F = np.arange(5.0, 31.0, 5.0)
    d = g * (1 - np.exp(-F / Fc)) + F / k
    rows = "".join(f"P0,+x,{t},sweep,{f:g},{f:g},0,0,{v * 1e3:.9f},0,0\n" for t in (1, 2) for f, v in zip(F, d))
    r = process(parse_measured_csv(HEADER + rows), case.with_params(**{"measurement.dial_resolution_m": 1e-9}))
    tol = 0.005
    pid = identify_preload(r, "+x", tolerance=tol)
    # brute force of the definition: smallest level above which the incremental ratios vary < tol
    expect = next(F[j] for j in range(len(F) - 2)
                  if np.std(r_ := (F[j + 1:] - F[j]) / (d[j + 1:] - d[j])) / np.mean(r_) <= tol)
    assert pid.preload_N == expect and expect > 5.0
    # above the identified preload the residual dead band changes the slope by < tol
    assert pid.stiffness_N_per_m == pytest.approx(k, rel=tol)


def test_preload_identification_needs_a_staircase(case):
    r = process(parse_measured_csv(HEADER + "P0,+x,1,preload,5,5,0,0,0.09,0,0\nP0,+x,1,total,20,20,0,0,0.36,0,0\n"), case)
    with pytest.raises(MeasuredDataError, match="sweep"):
        identify_preload(r, "+x")
