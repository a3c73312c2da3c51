"""``contact-patch``: two elastic blocks pressed flat transmit a uniform pressure (contact patch test).

Two identical-material blocks (side L = 10 mm, steel E = 210 GPa, ν = 0.3) touch on the plane z = 0;
the top face of the upper block carries a uniform pressure P = 100 MPa, the bottom face of the lower block
rests on rollers (u_z = 0), the planes x = 0 and y = 0 are symmetry planes. Frictionless contact.
Exact solution: uniaxial stress σ_zz = −P in both blocks, so the contact pressure is P at every slave
integration point. The interface meshes do not match: the upper (slave) block is one uniform refinement
of the mirror image of the lower (master) block, so every slave facet lies inside one master facet and the
Gauss-point-to-surface contact integrates the master shape functions exactly — the setting in which GPTS
passes the patch test. ``computed`` is the slave point pressure farthest from P; reference P.
"""
from __future__ import annotations

import time

import numpy as np
import skfem

from femcheck.fe.checks import CheckResult
from femcheck.fe.constraints import clamp
from femcheck.fe.contact.pairing import default_penalty, pair_surfaces
from femcheck.fe.elasticity import assemble_stiffness, assemble_traction, vector_basis
from femcheck.fe.newton import ContactProblem, solve_contact

NAME = "contact-patch"
#: relative error accepted at each mesh level (``femcheck check-solver`` fails above it)
TOLERANCE = {"coarse": 1e-9, "default": 1e-9, "fine": 1e-9}
TOLERANCE_REASON = "patch test: a uniform pressure is transmitted exactly by a consistent contact discretization (round-off only)"
E, NU = 210e9, 0.3
L = 0.01
P = 100e6
CELLS = {"coarse": 2, "default": 3, "fine": 4}


def two_blocks(n: int) -> tuple[skfem.MeshTet, int]:
    """Lower block [0,L]²×[−L,0] with n³ cells and upper block = mirror (z → −z) refined once.

    Returns the joined mesh (disjoint bodies, vertices not merged) and the number of lower-block tets.
    """
    x = np.linspace(0.0, L, n + 1)
    lower = skfem.MeshTet.init_tensor(x, x, x - L)
    up = skfem.MeshTet(lower.p * np.array([[1.0], [1.0], [-1.0]]), lower.t[[1, 0, 2, 3]]).refined()
    p = np.hstack([lower.p, up.p])
    t = np.hstack([lower.t, up.t + lower.p.shape[1]])
    return skfem.MeshTet(p, t), lower.t.shape[1]


def build(mesh_level: str = "default", penalty_factor: float = 10.0):
    """(problem, pair, basis) for the patch test at the given refinement."""
    mesh, n_lower = two_blocks(CELLS[mesh_level])
    basis = vector_basis(mesh, 2)
    K = assemble_stiffness(basis, E, NU)
    bf = mesh.boundary_facets()
    fc = mesh.p[:, mesh.facets[:, bf]].mean(axis=1)
    body = (mesh.f2t[0, bf] >= n_lower).astype(int)  # 0 lower, 1 upper
    tol = 1e-9 * L
    top = bf[np.isclose(fc[2], L, atol=tol)]
    bottom = bf[np.isclose(fc[2], -L, atol=tol)]
    slave = bf[np.isclose(fc[2], 0.0, atol=tol) & (body == 1)]
    master = bf[np.isclose(fc[2], 0.0, atol=tol) & (body == 0)]
    f = assemble_traction(skfem.FacetBasis(mesh, basis.elem, facets=top), [0.0, 0.0, -P])
    x_dofs = _dofs_on(basis, lambda X: np.isclose(X[0], 0.0, atol=tol), 0)
    y_dofs = _dofs_on(basis, lambda X: np.isclose(X[1], 0.0, atol=tol), 1)
    z_dofs = _dofs_on(basis, lambda X: np.isclose(X[2], -L, atol=tol), 2)
    C = clamp(basis.N, np.concatenate([x_dofs, y_dofs, z_dofs]))
    eps = default_penalty(mesh, slave, E, penalty_factor)
    pair = pair_surfaces(basis, slave, master, penalty_n=eps, friction=0.0, name="blocks")
    return ContactProblem(K=K, f=f, constraints=C, pairs=(pair,)), pair, basis


def _dofs_on(basis, where, component: int) -> np.ndarray:
    """Vector DOFs of one component (0 x, 1 y, 2 z) at the DOF locations where ``where(X)`` is true."""
    loc = basis.doflocs
    idx = np.flatnonzero(where(loc))
    return idx[idx % 3 == component]


def run(mesh: str = "default") -> CheckResult:
    t0 = time.perf_counter()
    problem, pair, basis = build(mesh)
    res = solve_contact(problem, 1, initial_closure=1e-12)
    p = res.pairs[0].pressure
    worst = p[np.argmax(np.abs(p - P))]
    return CheckResult(name=NAME, quantity="contact pressure at the worst slave point (Pa)", computed=float(worst),
                       reference=P, dofs=int(basis.N), iterations=int(sum(res.iterations_per_step)),
                       seconds=time.perf_counter() - t0,
                       detail={"slave_points": pair.n_points, "max_rel_deviation": float(np.max(np.abs(p - P)) / P),
                               "factorizations": res.timings["factorizations"],
                               "augmentations": sum(s.augmentations for s in res.steps), "solver": res.solver})
