"""Elasticity on tets: patch test (P1, P2), rigid-body modes, mass, stress, multi-material bar."""
import numpy as np
import pytest
import skfem

from femcheck.fe import constraints
from femcheck.fe.elasticity import (assemble_mass, assemble_stiffness, assemble_traction, dof_triplets,
                                    facet_area_weights, lame, rigid_body_modes, stress, vector_basis, von_mises)
from femcheck.fe.linear_solver import solve

E, NU = 210e9, 0.3


def _mesh():
    # a distorted box: interior vertices moved, so the patch test is not helped by a regular grid
    m = skfem.MeshTet.init_tensor(np.linspace(0, 1, 4), np.linspace(0, 0.5, 3), np.linspace(0, 0.5, 3))
    p = m.p.copy()
    inner = (p[0] > 0) & (p[0] < 1) & (p[1] > 0) & (p[1] < 0.5) & (p[2] > 0) & (p[2] < 0.5)
    p[:, inner] += 0.05 * np.array([[1.0], [-0.7], [0.4]])
    return skfem.MeshTet(p, m.t)


@pytest.mark.parametrize("method", ["vectorized", "skfem"])
@pytest.mark.parametrize("order", [1, 2])
def test_patch_linear_field_reproduced(order, method):
    mesh = _mesh()
    basis = vector_basis(mesh, order)
    K = assemble_stiffness(basis, E, NU, method=method)
    pts, trip = dof_triplets(basis)
    G = np.array([[1e-3, 2e-4, -3e-4], [5e-4, -2e-3, 1e-4], [0.0, 3e-4, 1.5e-3]])
    u_exact = np.zeros(basis.N)
    u_exact[trip] = pts @ G.T + np.array([1e-4, -2e-4, 3e-4])
    c = constraints.clamp(basis.N, basis.get_dofs().all(), u_exact[basis.get_dofs().all()])
    u = c.expand(solve(c.reduce_matrix(K), c.reduce_vector(np.zeros(basis.N), K)).x)
    # patch test: exact up to round-off (condition number ~1e6 at this size)
    assert np.abs(u - u_exact).max() <= 1e-10 * np.abs(u_exact).max()
    # constant stress = Hooke's law of the imposed strain everywhere
    eps = 0.5 * (G + G.T)
    lam, mu = lame(E, NU)
    sig = lam * np.trace(eps) * np.eye(3) + 2 * mu * eps
    s = stress(basis, u, E, NU)
    assert np.abs(s - sig[:, :, None, None]).max() <= 1e-8 * np.abs(sig).max()  # round-off in gradients


@pytest.mark.parametrize("order", [1, 2])
def test_rigid_body_modes_and_mass(order):
    basis = vector_basis(_mesh(), order)
    K = assemble_stiffness(basis, E, NU)
    M = assemble_mass(basis, 7800.0)
    B = rigid_body_modes(basis)
    assert np.abs(K @ B).max() <= 1e-12 * abs(K).max()  # zero strain energy up to round-off
    vol = 0.25
    for k in range(3):  # translational mass = ρ V exactly (consistent mass, exact quadrature)
        assert B[:, k] @ M @ B[:, k] == pytest.approx(7800.0 * vol, rel=1e-12)


@pytest.mark.parametrize("order", [1, 2])
def test_vectorized_assembly_is_the_weak_form_to_round_off(order):
    """The batched element matrices (B^T D B in the λ/μ split) are the skfem weak form: same matrix to
    round-off with per-element E, ν, exactly symmetric, rigid-body modes in the null space."""
    mesh = _mesh()
    basis = vector_basis(mesh, order)
    rng = np.random.default_rng(7)
    nel = mesh.t.shape[1]
    E_el, nu_el = rng.uniform(70e9, 210e9, nel), rng.uniform(0.2, 0.45, nel)
    K = assemble_stiffness(basis, E_el, nu_el)
    K0 = assemble_stiffness(basis, E_el, nu_el, method="skfem")
    scale = abs(K0).max()
    assert abs(K - K0).max() <= 1e-12 * scale  # same quadrature, different summation order: round-off
    assert abs(K - K.T).max() == 0.0  # symmetric by construction (averaged element matrices)
    B = rigid_body_modes(basis)
    # six rigid-body modes carry no strain energy (relative to |K| |B|, round-off)
    assert np.abs(K @ B).max() <= 1e-10 * scale * np.abs(B).max()
    # the quadratic form of a random field agrees too (the sum over all entries, not only the largest)
    x = rng.standard_normal(basis.N)
    assert x @ (K @ x) == pytest.approx(x @ (K0 @ x), rel=1e-12)
    with pytest.raises(ValueError, match="assembly method"):
        assemble_stiffness(basis, E, NU, method="fast")
    # a quadrature rule with negative weights (tet order 4) takes the branch without square roots
    b4 = vector_basis(mesh, order, intorder=4)
    K4, K40 = assemble_stiffness(b4, E_el, nu_el), assemble_stiffness(b4, E_el, nu_el, method="skfem")
    assert abs(K4 - K40).max() <= 1e-12 * abs(K40).max() and abs(K4 - K4.T).max() == 0.0
    # the consistent mass the same way: same matrix as the weak form, per-element density
    rho = rng.uniform(2700.0, 7800.0, nel)
    M = assemble_mass(basis, rho)
    M0 = assemble_mass(basis, rho, method="skfem")
    assert abs(M - M0).max() <= 1e-12 * abs(M0).max()
    assert abs(M - M.T).max() == 0.0


def test_von_mises_uniaxial_and_two_material_bar():
    """Bar of two materials in series under end traction: u_tip = σ (L1/E1 + L2/E2), σ_vM = σ."""
    L, a = 1.0, 0.1
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, L, 11), np.linspace(0, a, 3), np.linspace(0, a, 3))
    basis = vector_basis(mesh, 2)
    centers = mesh.p[:, mesh.t].mean(axis=1)
    E_el = np.where(centers[0] < 0.5, 200e9, 70e9)
    K = assemble_stiffness(basis, E_el, 0.0)
    end = skfem.FacetBasis(mesh, basis.elem, facets=mesh.facets_satisfying(lambda x: np.isclose(x[0], L)))
    sigma = 1e8
    f = assemble_traction(end, [sigma, 0, 0])
    assert f.sum() == pytest.approx(sigma * a * a, rel=1e-12)  # Σ consistent forces = traction × area
    pts, trip = dof_triplets(basis)
    root = np.isclose(pts[:, 0], 0.0)
    c = constraints.clamp(basis.N, np.r_[trip[root, 0], trip[:, 1], trip[:, 2]])  # uniaxial, ν = 0
    u = c.expand(solve(c.reduce_matrix(K), c.reduce_vector(f)).x)
    tip = trip[np.isclose(pts[:, 0], L), 0]
    # linear field in each material: exact up to round-off
    assert u[tip] == pytest.approx(np.full(tip.size, sigma * (0.5 / 200e9 + 0.5 / 70e9)), rel=1e-9)
    assert von_mises(basis, u, E_el, 0.0) == pytest.approx(np.full(mesh.t.shape[1], sigma), rel=1e-9)
    w = facet_area_weights(end)
    assert w.sum() == pytest.approx(a * a, rel=1e-12)  # consistent area shares add to the area


def test_bad_material_is_rejected():
    with pytest.raises(ValueError, match="nu"):
        lame(210e9, 0.5)
    basis = vector_basis(_mesh(), 1)
    with pytest.raises(ValueError, match="one per element"):
        assemble_stiffness(basis, np.ones(3), 0.3)
