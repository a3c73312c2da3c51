"""Multipoint constraints: clamp, RBE2 (rigid motion exact), RBE3 (resultant wrench exact), combine."""
import numpy as np
import pytest
import skfem

from femcheck.fe import constraints as C
from femcheck.fe.beam import BeamSection, assemble_beam_stiffness, beam_dofs, line_mesh
from femcheck.fe.elasticity import (assemble_stiffness, assemble_traction, dof_triplets, facet_area_weights,
                                    vector_basis)
from femcheck.fe.linear_solver import solve

L, H, B = 0.1, 0.02, 0.03


@pytest.fixture(scope="module")
def block():
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, L, 6), np.linspace(0, H, 3), np.linspace(0, B, 3))
    basis = vector_basis(mesh, 2)
    K = assemble_stiffness(basis, 210e9, 0.3)
    tip_facets = mesh.facets_satisfying(lambda x: np.isclose(x[0], L))
    fb = skfem.FacetBasis(mesh, basis.elem, facets=tip_facets, intorder=4)
    pts, trip = dof_triplets(basis, basis.get_dofs(tip_facets).all())
    return mesh, basis, K, fb, pts, trip


def _solve(c, K, f):
    return c.expand(solve(c.reduce_matrix(K), c.reduce_vector(f, K)).x)


def test_rbe2_reproduces_rigid_motion(block):
    mesh, basis, K, _, pts, trip = block
    ndof, ref = C.append_reference_nodes(basis.N, 1)
    x_r = np.array([0.13, 0.01, 0.015])
    motion = np.array([1e-5, -2e-5, 3e-5, 1e-4, -2e-4, 3e-4])  # (u; θ) m, rad
    c = C.combine(C.rigid_coupling(ndof, ref[0], x_r, pts, trip), C.clamp(ndof, ref[0], motion))
    u = _solve(c, K, np.zeros(ndof))
    P, T = dof_triplets(basis)
    expected = motion[:3] + np.cross(motion[3:], P - x_r)
    # the free body follows its coupled face rigidly: exact up to round-off
    assert np.abs(u[T] - expected).max() <= 1e-9 * np.abs(expected).max()


def test_rbe3_transmits_resultant_wrench_and_matches_traction(block):
    mesh, basis, K, fb, pts, trip = block
    ndof, ref = C.append_reference_nodes(basis.N, 1)
    x_r = np.array([0.15, 0.005, 0.02])  # off the face, so moments are transferred too
    w = facet_area_weights(fb)[trip[:, 0] // 3]
    root = basis.get_dofs(lambda x: np.isclose(x[0], 0.0)).all()
    W = np.array([10.0, -20.0, 30.0, 0.5, -0.7, 0.9])
    c = C.combine(C.distributing_coupling(ndof, ref[0], x_r, pts, trip, w), C.clamp(ndof, root))
    f = C.nodal_wrench(ndof, ref[0], W)
    u = _solve(c, K, f)
    R = c.reactions(K, u, f)
    Pr, Tr = dof_triplets(basis, root)
    resultant = np.r_[R[Tr].sum(0), np.cross(Pr - x_r, R[Tr]).sum(0)]
    # equilibrium of the whole body about x_r: exact up to round-off
    assert np.abs(resultant + W).max() <= 1e-9 * np.abs(W).max()
    # a pure force at the face centroid through area weights = the consistent uniform traction
    xc = np.array([L, H / 2, B / 2])
    c2 = C.combine(C.distributing_coupling(ndof, ref[0], xc, pts, trip, w), C.clamp(ndof, root))
    F = np.array([0.0, 100.0, 0.0])
    u_rbe3 = _solve(c2, K, C.nodal_wrench(ndof, ref[0][:3], F))
    u_trac = _solve(C.clamp(basis.N, root), K, assemble_traction(fb, F / (H * B)))
    # RBE3 adds no stiffness: same field to round-off
    assert np.abs(u_rbe3[:basis.N] - u_trac).max() <= 1e-9 * np.abs(u_trac).max()


def test_rbe2_joins_beam_rotations():
    """Two beams joined by an RBE2 at coincident end nodes behave as one continuous beam."""
    E, G, sec = 210e9, 80.77e9, BeamSection.circle(0.01)
    nodes, el = line_mesh([0, 0, 0], [0.2, 0, 0], 4)
    K1 = assemble_beam_stiffness(nodes, el, E, G, sec)
    two = np.r_[nodes[:3], nodes[2:]]  # node 2 duplicated as node 3
    el2 = np.array([[0, 1], [1, 2], [3, 4], [4, 5]])
    K2 = assemble_beam_stiffness(two, el2, E, G, sec)
    f1 = C.nodal_wrench(K1.shape[0], beam_dofs([4])[0], [0, 30, -20, 1, 2, 3])
    f2 = C.nodal_wrench(K2.shape[0], beam_dofs([5])[0], [0, 30, -20, 1, 2, 3])
    u1 = _solve(C.clamp(K1.shape[0], beam_dofs([0])), K1, f1)
    d3 = beam_dofs([3])[0]
    c = C.combine(C.clamp(K2.shape[0], beam_dofs([0])),
                  C.rigid_coupling(K2.shape[0], beam_dofs([2])[0], two[2], two[3:4], d3[None, :3], d3[None, 3:]))
    u2 = _solve(c, K2, f2)
    assert u2[beam_dofs([5])[0]] == pytest.approx(u1[beam_dofs([4])[0]], rel=1e-9)  # round-off


def test_chained_constraints_and_errors():
    # RBE2 slave DOFs depend on a reference node that is itself prescribed: resolved by substitution
    ndof = 6 + 3
    c = C.combine(C.rigid_coupling(ndof, np.arange(6), [0, 0, 0], [[1.0, 0, 0]], [[6, 7, 8]]),
                  C.clamp(ndof, np.arange(6), [0, 0, 0, 0, 0, 0.1]))
    assert c.nfree == 0
    assert c.g[6:] == pytest.approx([0.0, 0.1, 0.0], abs=1e-15)  # θ_z × r = (0, 0.1, 0)
    with pytest.raises(ValueError, match="constrained twice"):
        C.combine(C.clamp(ndof, [6]), C.clamp(ndof, [6]))
    with pytest.raises(ValueError, match="cyclic"):  # u0 = u1, u1 = u0
        C.combine(C.rigid_coupling(ndof, np.arange(6), [0, 0, 0], [[0.0, 0, 0]], [[6, 7, 8]]),
                  C.rigid_coupling(ndof, [6, 7, 8, 3, 4, 5], [0, 0, 0], [[0.0, 0, 0]], [[0, 1, 2]]))
    with pytest.raises(ValueError, match="collinear"):
        C.distributing_coupling(9 + 6, np.arange(9, 15), [0, 0, 0], [[0, 0, 0], [1, 0, 0], [2, 0, 0]],
                                np.arange(9).reshape(3, 3))


def test_follow_moves_dofs_with_their_leader_and_carries_its_force():
    # three unit springs in parallel between the clamped DOFs 0..2 and the DOFs 3..5, which follow the leader 6
    # with offsets b; a force F on the leader: u_6 = F / 3 (springs in parallel) and u_i = u_6 + b_i exactly
    ndof, F = 7, 3.0
    b = np.array([0.0, 1e-3, -2e-3])
    c = C.combine(C.clamp(ndof, [0, 1, 2]), C.follow(ndof, [3, 4, 5], 6, b))
    assert c.free.tolist() == [6]
    K = np.zeros((ndof, ndof))
    for i in range(3):
        K[np.ix_([i, i + 3], [i, i + 3])] += [[1.0, -1.0], [-1.0, 1.0]]
    f = np.zeros(ndof)
    f[6] = F
    T = c.T.toarray()
    q = np.linalg.solve(T.T @ K @ T, T.T @ (f - K @ c.g))
    u = T @ q + c.g
    # reduced equilibrium Tᵀ K T q = Tᵀ (f − K g): the offsets shift the springs' lengths, their sum Σ b_i = −1e-3
    # pulls the leader by +1e-3 / 3 on top of F / 3 (exact arithmetic, rounding only)
    assert u[6] == pytest.approx(F / 3 - b.sum() / 3, rel=1e-14)
    assert u[3:6] == pytest.approx(u[6] + b, rel=1e-14, abs=1e-18)
    assert u[:3] == pytest.approx(0.0, abs=0)
    with pytest.raises(ValueError, match="cyclic"):  # a DOF cannot follow itself
        C.follow(ndof, [6], 6)
