"""``friction-block``: Coulomb stick below μN, slide at μN (seed 004 §3.2.2–3.2.3).

A steel block (W × W × H, W = 10 mm, H = 2.5 mm) rests on an equal block clamped at its bottom; the
contact is Coulomb with μ = 0.3 (AL penalty, Gauss-point-to-surface, conforming interface).
The top face carries the normal load N = 1 kN as a uniform pressure; the plane y = 0 is a symmetry plane.

* stick case: a uniform tangential traction of total T = 0.5 μN (x) on the top face. Expected: every
  closed slave point sticks, the friction force Σ w t_x equals T and no point slips (|s − s_ref| ≤ tol).
* slide case: the top face is displaced by U = 20 µm in x (well beyond the elastic shear of the block).
  Expected: every closed point slides and the friction force — the tangential reaction — is μN.

``computed`` = the horizontal (x) reaction at the displaced top face in the slide case (N), from the
global equilibrium ``r = K u - f`` at the prescribed DOFs; reference μN. Unlike Σ w ‖t‖ over the contact
points (which the return mapping sets to μ p point by point), the reaction passes through the whole elastic
block, the contact assembly and the solver, so a wrong friction term, normal pressure or weight shows in it.
The clamped lower block and the free upper block expand differently under N (Poisson), so a small part of
the friction acts in y: ``R_x`` is below μN by the cosine of that angle (< 1e-3 relative here). The stick case
(friction force in x = T by equilibrium, all points STICK, residual slip) is in ``detail``.
"""
from __future__ import annotations

import time

import numpy as np
import skfem

from femcheck.fe.checks import CheckResult
from femcheck.fe.checks._graded_mesh import join, mirror_z
from femcheck.fe.constraints import clamp
from femcheck.fe.contact import status as st
from femcheck.fe.contact.pairing import default_penalty, pair_surfaces
from femcheck.fe.elasticity import assemble_stiffness, assemble_traction, vector_basis
from femcheck.fe.newton import ContactProblem, solve_contact

NAME = "friction-block"
E, NU = 210e9, 0.3
W, H = 0.01, 0.0025
MU = 0.3
N_LOAD = 1000.0
U_SLIDE = 20e-6
CELLS = {"coarse": (3, 1), "default": (4, 2), "fine": (6, 2)}
#: R_x = μN cos(angle of the y friction share): below 1e-3 relative; 1 % leaves room for the penalty's
#: elastic slip and flags a wrong friction coefficient, normal load or reaction
TOLERANCE = {"coarse": 1e-2, "default": 1e-2, "fine": 1e-2}
TOLERANCE_REASON = "Coulomb sliding: R_x = μN up to the y share of friction from the Poisson mismatch (< 1e-3)"


def build(level: str = "default", case: str = "slide", tangential_ratio: float = 0.5):
    """(problem, pair, basis) for ``case`` "stick" (force T = ratio · μN) or "slide" (displacement U)."""
    nxy, nz = CELLS[level]
    x = np.linspace(0.0, W, nxy + 1)
    lower = skfem.MeshTet.init_tensor(x, x, np.linspace(-H, 0.0, nz + 1))
    mesh, n_lower = join(lower, mirror_z(lower))
    basis = vector_basis(mesh, 2)
    K = assemble_stiffness(basis, E, NU)
    tol = 1e-9 * W
    bf = mesh.boundary_facets()
    fc = mesh.p[:, mesh.facets[:, bf]].mean(axis=1)
    upper_f = mesh.f2t[0, bf] >= n_lower
    top = bf[np.isclose(fc[2], H, atol=tol)]
    slave = bf[upper_f & np.isclose(fc[2], 0.0, atol=tol)]
    master = bf[~upper_f & np.isclose(fc[2], 0.0, atol=tol)]
    fb = skfem.FacetBasis(mesh, basis.elem, facets=top)
    traction = [0.0, 0.0, -N_LOAD / W**2]
    if case == "stick":
        traction[0] = tangential_ratio * MU * N_LOAD / W**2
    f = assemble_traction(fb, traction)
    X = basis.doflocs
    comp = np.arange(basis.N) % 3
    bottom = np.flatnonzero(np.isclose(X[2], -H, atol=tol))
    sym_y = np.flatnonzero(np.isclose(X[1], 0.0, atol=tol) & (comp == 1))
    sym_y = np.setdiff1d(sym_y, bottom)
    dofs, vals = [bottom, sym_y], [np.zeros(bottom.size), np.zeros(sym_y.size)]
    if case == "slide":
        top_x = np.flatnonzero(np.isclose(X[2], H, atol=tol) & (comp == 0))
        dofs.append(top_x)
        vals.append(np.full(top_x.size, U_SLIDE))
    elif case != "stick":
        raise ValueError(f"case = {case!r}; expected 'stick' or 'slide'")
    C = clamp(basis.N, np.concatenate(dofs), np.concatenate(vals))
    eps = default_penalty(mesh, slave, E, 10.0)
    pair = pair_surfaces(basis, slave, master, penalty_n=eps, friction=MU, name="block-block")
    return ContactProblem(K=K, f=f, constraints=C, pairs=(pair,)), pair, basis


def friction_force(pair, state) -> np.ndarray:
    """Total friction force on the slave (x, y, z) N: Σ w (t1 t_1 + t2 t_2)."""
    tvec = state.traction[:, :1] * pair.t1 + state.traction[:, 1:] * pair.t2
    return (pair.weights[:, None] * tvec).sum(axis=0)


def run(mesh: str = "default") -> CheckResult:
    t0 = time.perf_counter()
    out = {}
    iters = 0
    for case in ("stick", "slide"):
        problem, pair, basis = build(mesh, case)
        res = solve_contact(problem, 2, initial_closure=1e-12)
        s = res.pairs[0]
        ff = friction_force(pair, s)
        out[case] = {"friction_force_x_N": float(abs(ff[0])),
                     "friction_magnitude_sum_N": float(np.sum(pair.weights * np.linalg.norm(s.traction, axis=1))),
                     "normal_force_N": s.force(pair),
                     "status": st.counts(s.status), "max_stick_slip_m": float(np.max(np.linalg.norm(s.slip[s.status == st.STICK], axis=1),
                                                     initial=0.0)),
                     "iterations": res.iterations_per_step, "factorizations": res.timings["factorizations"]}
        if case == "slide":
            X = basis.doflocs
            top_x = np.flatnonzero(np.isclose(X[2], H, atol=1e-9 * W) & (np.arange(basis.N) % 3 == 0))
            out[case]["top_reaction_x_N"] = float(abs(res.reactions(problem)[top_x].sum()))
        iters += sum(res.iterations_per_step)
    out["stick"]["applied_T_N"] = 0.5 * MU * N_LOAD
    return CheckResult(name=NAME, quantity="horizontal reaction at the displaced top face while sliding (N)",
                       computed=out["slide"]["top_reaction_x_N"], reference=MU * N_LOAD, dofs=int(basis.N),
                       iterations=iters, seconds=time.perf_counter() - t0, detail=out)
