"""Issue 17 item 4 (VTU bullet): the written VTU carries von Mises stress, the strain-energy density and the
reactions at the clamps, read back with meshio, and has the permissions of a normal file."""
import os
import stat

import meshio
import numpy as np
import pytest
import skfem

from femcheck.fe import constraints
from femcheck.fe.elasticity import assemble_stiffness, assemble_traction, vector_basis
from femcheck.fe.linear_solver import factorize
from femcheck.fe.results import ElasticResult


@pytest.fixture(scope="module", params=[(1, 0.3, (1.0, 0.0, 0.0)), (2, 0.3, (0.0, 1.0, 0.0)), (2, 0.25, (0.3, -0.4, 0.8))])
def cantilever(request):
    """P1/P2 clamped box under a uniform end traction of random-ish direction; (result, K, u, f, load N)."""
    order, nu, direction = request.param
    Lx, h = 0.08, 0.01
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, Lx, 9), np.linspace(0, h, 3), np.linspace(0, h, 3))
    basis = vector_basis(mesh, order)
    E = 70e9
    K = assemble_stiffness(basis, E, nu)
    tip = skfem.FacetBasis(mesh, basis.elem, facets=mesh.facets_satisfying(lambda x: np.isclose(x[0], Lx)),
                           intorder=2 * order)
    q = 1e6 * np.asarray(direction)  # Pa
    f = assemble_traction(tip, list(q))
    fixed = basis.get_dofs(lambda x: np.isclose(x[0], 0.0)).all()
    c = constraints.clamp(basis.N, fixed)
    u = c.expand(factorize(c.reduce_matrix(K)).solve(c.reduce_vector(f)))
    res = ElasticResult(basis, u, E, nu, reactions=ElasticResult.reaction_forces(K, u, f, fixed))
    return res, K, u, f, q * h * h


def test_vtu_strain_energy_and_reactions(cantilever, tmp_path):
    res, K, u, f, load = cantilever
    back = meshio.read(res.write_vtu(tmp_path / "c.vtu"))
    w_e = back.cell_data["strain_energy_density_J_m3"][0]
    vol = res.element_volumes()
    # Clapeyron: ∫ w dV = ½ uᵀf; the element quadrature integrates the polynomial strain energy exactly,
    # so only the round-off of the direct solve (condition ~1e7) separates them
    assert np.isclose(w_e @ vol, 0.5 * u @ f, rtol=1e-8)
    assert np.all(w_e >= 0)  # energy density of a positive definite material
    r = back.point_data["reaction_force_N"]
    # the clamp balances the applied end load (global equilibrium), to solver round-off
    assert np.allclose(r.sum(axis=0), -load, rtol=0, atol=1e-8 * np.linalg.norm(load))
    clamp = np.isclose(back.points[:, 0], 0.0)
    assert np.all(r[~clamp] == 0.0)  # reactions only where the part is clamped
    vm = back.point_data["von_mises_Pa"]
    assert vm.shape == (back.points.shape[0],) and np.all(vm >= 0)
    # the vertex-averaged energy density is bounded by the element values around it
    w_n = back.point_data["strain_energy_density_J_m3"]
    assert w_n.max() <= w_e.max() * (1 + 1e-12) and w_n.min() >= w_e.min() * (1 - 1e-12)


def test_vtu_has_normal_permissions(cantilever, tmp_path):
    res = cantilever[0]
    old = os.umask(0o022)
    try:
        p = res.write_vtu(tmp_path / "perm.vtu")
    finally:
        os.umask(old)
    assert stat.S_IMODE(os.stat(p).st_mode) == 0o644  # 0666 less umask 022, not mkstemp's 0600


def test_device_clamp_reactions_balance_the_platform_load(case, tmp_path):
    """Device VTU: the six rail-clamp reactions balance the applied TCP force (simplified level, rigid
    joints, beam link; solid P2 guideways at a coarse mesh), and the per-tet fields are written."""
    from femcheck.fe_device.device_model import build_link, guideway_task, point_geometry, point_model, solve_point
    from femcheck.fe_device.results import clamp_reactions, write_point_vtu
    legs = point_geometry(case, ["P0"])
    gws = [guideway_task(case, s, "solid", 0.008) for s in legs.slider[0]]
    model = point_model(case, legs, 0, "P0", gws, build_link(case, "beam", None))
    res = solve_point(case, model, levels=("simplified",), joints=("rigid",), directions=("+x", "-z"))
    P = case.loads.simplified_test_N
    R = clamp_reactions(model, res)
    for d, unit in (("+x", [1.0, 0, 0]), ("-z", [0, 0, -1.0])):
        F = R[f"simplified_rigid_{d}"][:, :3].sum(axis=0)
        # equilibrium of the whole device (no gravity): round-off of the condensed solve
        np.testing.assert_allclose(F, -P * np.asarray(unit), atol=1e-8 * P)
    mat = ((case.guideway.material.E_Pa, case.guideway.material.nu),
           (case.proximal_link.material.E_Pa, case.proximal_link.material.nu))
    assert write_point_vtu(tmp_path / "P0.vtu", model, res, mat)
    back = meshio.read(tmp_path / "P0.vtu")
    r = back.point_data["clamp_reaction_simplified_rigid_+x_N"]
    # the written clamp forces sum to the applied load (float64 kept: round-off only)
    np.testing.assert_allclose(r.sum(axis=0), [-P, 0, 0], atol=1e-8 * P)
    assert np.count_nonzero(np.abs(r).sum(axis=1)) < 0.2 * len(r)  # only on the clamp faces
    w = back.cell_data["strain_energy_density_simplified_rigid_+x_J_m3"][0]
    vm = back.cell_data["von_mises_simplified_rigid_+x_Pa"][0]
    assert np.all(w >= 0) and np.all(vm >= 0) and vm.max() > 0
    assert stat.S_IMODE(os.stat(tmp_path / "P0.vtu").st_mode) == 0o666 & ~_umask()


def _umask():
    m = os.umask(0)
    os.umask(m)
    return m


def test_constant_strain_tet_fields_closed_form():
    """tet_fields: a uniaxial strain field u_x = ε x in one tetrahedron gives σ_vM = E ε and w = ½ E ε²
    for ν = 0 (exact: the field is linear)."""
    from femcheck.fe_device.results import tet_fields
    pts = \
        np.array([[0, 0, 0], [1e-2, 0, 0], [0, 2e-2, 0], [0, 0, 3e-2]])
    eps = 1e-3
    U = np.zeros((4, 3))
    U[:, 0] = eps * pts[:, 0]
    vm, w = tet_fields(pts, np.array([[0, 1, 2, 3]]), U, np.array([200e9]), np.array([0.0]))
    assert np.isclose(vm[0], 200e9 * eps, rtol=1e-12) and np.isclose(w[0], 0.5 * 200e9 * eps**2, rtol=1e-12)
