"""1-D bar on a normal contact spring (seed 004 eqs. 20–31): forward/inverse, sensitivity, FE cross-check."""
import numpy as np
import pytest

from femcheck.contact_id.bar_on_spring import (Bar, ContactIdError, frequency_roots, identify_normal_stiffness,
                                               log_sensitivity, natural_frequencies_Hz)

BAR = Bar(length_m=0.5, area_m2=5.067e-4, E_Pa=200e9, density_kg_m3=7850.0)


def test_roots_satisfy_eq30_and_limits():
    beta = np.logspace(-3, 3, 200)
    x = frequency_roots(beta, 6)
    # residual of tan x = beta / x: bisection to 1e-18 plus Newton polish -> round-off level
    assert np.max(np.abs(x * np.sin(x) - beta[:, None] * np.cos(x)) / (1 + beta[:, None])) < 1e-12
    # limits: beta = 0 free-free bar x = (i-1) pi, beta = inf fixed end x = (i-1/2) pi (exact by construction)
    assert np.allclose(frequency_roots(0.0, 3), [0, np.pi, 2 * np.pi], atol=0)
    assert np.allclose(frequency_roots(np.inf, 3), [0.5 * np.pi, 1.5 * np.pi, 2.5 * np.pi], atol=0)
    # published root beta = 1, mode 1: 0.8603335890 (Abramowitz & Stegun Table 4.19); 1e-9 = table digits
    assert abs(frequency_roots(1.0, 1)[0] - 0.8603335890) < 1e-9


def test_small_beta_is_mass_on_spring():
    k = 1e-3 * BAR.structure_stiffness_N_m
    f1 = natural_frequencies_Hz(BAR, k, 1)[0]
    # rigid-mass limit f = sqrt(k/m)/2pi; relative error ~ beta/6 = 1.7e-4 -> 5e-4 tolerance
    assert abs(f1 / (np.sqrt(k / BAR.mass_kg) / (2 * np.pi)) - 1) < 5e-4


@pytest.mark.parametrize("k_n", [2e6, 5e7, 2e8, 3e9])
def test_forward_inverse_roundtrip(k_n):
    f = natural_frequencies_Hz(BAR, k_n, 4)
    r = identify_normal_stiffness(BAR, f)
    # acceptance: identified k_n within 0.1 % of the k_n used for noise-free frequencies (all modes)
    assert np.max(np.abs(r.k_n_N_m / k_n - 1)) < 1e-3
    assert r.consistent


def test_sensitivity_matches_finite_difference():
    beta = np.array([0.05, 0.7, 8.0])
    h = 1e-6
    x = frequency_roots(beta, 4)
    fd = (np.log(frequency_roots(beta * (1 + h), 4)) - np.log(frequency_roots(beta * (1 - h), 4))) / (np.log1p(h) - np.log1p(-h))
    # central difference error O(h^2) plus round-off 1e-16/1e-6 -> 1e-8 absolute
    assert np.max(np.abs(fd - log_sensitivity(beta, x))) < 1e-8


def test_most_sensitive_mode_depends_on_error_model():
    f = natural_frequencies_Hz(BAR, 5.0 * BAR.structure_stiffness_N_m, 3)
    rel = identify_normal_stiffness(BAR, f, sigma_f_Hz=0.0, sigma_f_rel=1e-3)
    ab = identify_normal_stiffness(BAR, f, sigma_f_Hz=1.0, sigma_f_rel=0.0)
    assert rel.modes[rel.best] == 1 == rel.modes[np.argmax(rel.sensitivity)]  # relative error: max d ln f / d ln k
    assert ab.modes[ab.best] == ab.modes[np.argmax(ab.df_dlnk_Hz)] != 1  # absolute error in Hz: max df/dlnk (seed: f3)


def test_inverse_rejects_impossible_frequency():
    top = 0.5 * np.pi * BAR.hz_per_unit_x()  # mode-1 limit for a rigid ground
    with pytest.raises(ContactIdError, match="outside"):
        identify_normal_stiffness(BAR, [1.01 * top])
    with pytest.raises(ContactIdError, match="expected finite values > 0"):
        identify_normal_stiffness(BAR, [-5.0])
    with pytest.raises(ContactIdError, match="mode number"):
        identify_normal_stiffness(BAR, [100.0, 6000.0], modes=[1])
    with pytest.raises(ContactIdError, match="bar.length_m"):
        Bar(0.0, 1e-4, 200e9, 7850)


def test_fe_bar_on_springs_matches_1d():
    """Quarter of a slender square bar (symmetry planes y=0, z=0 leave only doubly symmetric modes:
    the axial ones), eq. 44 normal springs on the end face, hex2 FE vs eq. 30."""
    from femcheck.contact_id.specimen_fe import (Patch, _facet_basis, assemble_block, component_dofs,
                                                 normal_spring_form, patch_facets, solve_modes)
    from skfem import asm
    l, a = 0.5, 0.02
    bar = Bar(l, a * a, 200e9, 7850.0)
    blk = assemble_block((l, a / 2, a / 2), (10, 1, 1), 200e9, 0.29, 7850.0, "hex2")
    Kn1 = asm(normal_spring_form(), _facet_basis(blk, patch_facets(blk, Patch("x+"))))
    fixed = np.concatenate([component_dofs(blk, patch_facets(blk, Patch("y-")), 1),
                            component_dofs(blk, patch_facets(blk, Patch("z-")), 2)])
    for beta in (0.1, 1.0, 10.0):
        k_n = beta * bar.structure_stiffness_N_m
        fe = solve_modes(blk.K + (k_n / (a * a)) * Kn1, blk.M, fixed, 3).frequencies_Hz
        # acceptance 1 %: measured < 0.05 % (Love lateral-inertia correction + discretization)
        assert np.max(np.abs(fe / natural_frequencies_Hz(bar, k_n, 3) - 1)) < 1e-2
