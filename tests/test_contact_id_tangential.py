"""FE specimen on tangential contact springs (seed 004 §4.3, eq. 44): relation, monotonicity, inversion."""
import numpy as np
import pytest

from femcheck.case import load_case
from femcheck.contact_id.tangential import build_model, identify_tangential_stiffness, modal_at, relation

CASE = "cases/contact_specimen.toml"


@pytest.fixture(scope="module")
def coarse():
    c = load_case(CASE).with_params(**{"fe.element": "hex1", "fe.divisions": [6, 4, 2]})
    return build_model(c.specimen, c.fe)


@pytest.fixture(scope="module")
def sweep(coarse):
    return relation(coarse, np.logspace(6, 11, 16))


def test_relation_monotone(sweep):
    # Courant–Fischer: K_C is PSD and linear in k_t -> every sorted frequency non-decreasing
    assert np.all(sweep.is_monotone())
    assert np.all(np.diff(sweep.frequencies_Hz[:, 0]) > 0)  # mode 1 strictly increasing


def test_soft_contact_limit_is_rigid_block_on_springs(coarse):
    f, s = modal_at(coarse, 1e6)
    # k_t = 1e6 N/m is ~1e7 times softer than the block in shear: rigid translation f = sqrt(2 k_t / m)/2pi
    # holds to ~1e-7; 1e-5 allows eigen-solver round-off
    assert np.max(np.abs(f[:3] / coarse.rigid_translation_Hz(1e6) - 1)) < 1e-5
    assert np.max(np.abs(s[:3] - 0.5)) < 1e-5  # f ~ sqrt(k_t): d ln f / d ln k_t = 1/2


def test_sensitivity_matches_finite_difference(coarse):
    k, h = 3e9, 1e-4
    _, s = modal_at(coarse, k)
    fp, _ = modal_at(coarse, k * (1 + h))
    fm, _ = modal_at(coarse, k * (1 - h))
    fd = (np.log(fp) - np.log(fm)) / (np.log1p(h) - np.log1p(-h))
    # Hellmann–Feynman vs central difference: O(h^2) truncation + solver round-off ~1e-10/1e-4
    assert np.max(np.abs(fd - s)) < 1e-4


@pytest.mark.parametrize("k_t", [4e7, 2.5e9])
def test_inversion_recovers_k_t(coarse, sweep, k_t):
    f, _ = modal_at(coarse, k_t)
    r = identify_tangential_stiffness(coarse, f[[0, 3]], [1, 4], sweep=sweep)
    # acceptance 2 %; Newton on the FE model itself converges to 1e-7 in ln f
    assert np.max(np.abs(r.k_t_N_m / k_t - 1)) < 2e-2
    assert r.modes[r.best] == 1


def test_inversion_outside_band_names_frequency(coarse, sweep):
    from femcheck.contact_id.bar_on_spring import ContactIdError
    with pytest.raises(ContactIdError, match="outside"):
        identify_tangential_stiffness(coarse, [1.0], sweep=sweep)


@pytest.mark.slow
def test_inversion_across_meshes():
    """Frequencies from the default hex2 (8, 6, 2) model, inverted with a coarse hex1 model: the
    discretization difference must stay inside the 2 % acceptance."""
    c = load_case(CASE)
    fine = build_model(c.specimen, c.fe)
    cc = c.with_params(**{"fe.element": "hex1", "fe.divisions": [12, 8, 3]})
    coarse = build_model(cc.specimen, cc.fe)
    sw = relation(coarse, np.logspace(6, 11, 16))
    for k_t in (1e8, 3e9):
        f, _ = modal_at(fine, k_t)
        r = identify_tangential_stiffness(coarse, f[:1], sweep=sw)
        assert abs(r.k_t_N_m_best / k_t - 1) < 2e-2
