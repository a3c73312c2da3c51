"""Hertz sphere on a flat block: approach and contact radius vs Johnson's closed form (issue 5 acceptance).

Identical steel (E = 210 GPa, ν = 0.3), sphere radius R = 5 mm on a flat, F = 15 N and 50 N (two load
steps of one solve). Quarter model (symmetry planes x = 0, y = 0), P2 tetrahedra graded toward the contact.

Model. Hertz theory treats both bodies as elastic half-spaces with the profile z = r²/2R. Each body is a
box of side L = 1.5 mm (≈ 13–19 contact radii); the upper box's bottom face is mapped onto the sphere
z = R − sqrt(R² − r²). The truncation faces (x = L, y = L, z = ±L) carry the Boussinesq displacement of
the point load F (Johnson eq. 3.21; error O(a²/L²) against the Hertz pressure), so the model is a
half-space truncated without a stiffness error. On the upper body that field is superposed on a rigid
translation Δ, one extra unknown carrying the external force −F/4 (quarter). Δ is then exactly the mutual
approach of distant points of Hertz theory: δ = −Δ.

Singularity. Under force control Δ is free until the sphere touches the block; the solver closes the
slave points whose initial gap is within 1e-12 m of the smallest one in the first iteration (an initial
closure step: penalty springs in the iteration matrix only), after which the true contact status holds Δ.

Honest extraction. Besides δ = −Δ, the approach is extracted as δ(d) = approach of the axis points at
depth d in both bodies + 2 v(d), v the half-space axis displacement under the Hertz pressure
(:func:`femcheck.fe.contact.half_space.hertz_axis_displacement`); ``detail["depth_extraction"]`` lists it for
several depths — it must not depend on d. Contact radius: a = sqrt(4 A_c/π) with A_c the area of the
closed slave integration points (quarter) is reported as ``a_area_m``; ``a_m`` (compared with Hertz) is the
radius of the outermost closed slave point, with the bracket [outermost closed, innermost open].
The area estimate is biased low when the Gauss-point pressure oscillates and opens points inside the
contact zone (seen at 50 N where the contact reaches the graded elements).

``computed`` = approach at 15 N (the smaller, harder-to-resolve contact); the 50 N values are in detail.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np
import scipy.sparse as sp

from femcheck.compliance.hertz_point_contact import effective_modulus
from femcheck.fe.checks import CheckResult
from femcheck.fe.checks._graded_mesh import dof_body, join, mirror_z, radial_box
from femcheck.fe.constraints import Constraints
from femcheck.fe.contact.half_space import boussinesq, hertz_axis_displacement, hertz_point
from femcheck.fe.contact.pairing import default_penalty, pair_surfaces
from femcheck.fe.elasticity import assemble_stiffness, vector_basis
from femcheck.fe.newton import ContactProblem, solve_contact

NAME = "hertz-sphere"
E, NU = 210e9, 0.3
R = 5e-3
L = 1.5e-3
LOADS_N = (15.0, 50.0)
#: cube shells n per body, fine shell width h0 (m), number of fine shells (radial_box)
LEVELS = {"coarse": (7, 30e-6, 4), "default": (9, 20e-6, 5), "fine": (11, 15e-6, 7)}


@dataclasses.dataclass(frozen=True)
class HertzModel:
    """Assembled quarter model: problem, pair, basis, index of the approach DOF Δ, timings (s)."""

    problem: ContactProblem
    pair: object
    basis: object
    delta_dof: int
    n_lower: int
    assembly_s: float
    mesh_s: float


def sphere_profile(r):
    """Sphere surface height above its lowest point (m): R − sqrt(R² − r²)."""
    return R - np.sqrt(R * R - np.square(r))


def make_mesh(level: str):
    """(mesh, n_lower): lower block [0,L]²×[−L,0] (master) and the sphere-capped upper block (slave)."""
    n, h0, n_fine = LEVELS[level]
    cube = radial_box(L, n, h0, n_fine)
    lower = mirror_z(cube)
    p = cube.p.copy()
    r = np.hypot(p[0], p[1])
    p[2] = p[2] + sphere_profile(r) * (1.0 - p[2] / L)
    upper = type(cube)(p, cube.t)
    return join(lower, upper)


def _far_field_constraints(basis, body, F, delta_dof, tol):
    """u = T q + g: symmetry planes, Boussinesq field on the truncation faces, Δ on the upper far field."""
    ndof = basis.N + 1
    X = basis.doflocs
    comp = np.arange(basis.N) % 3
    r = np.hypot(X[0], X[1])
    outer = (np.isclose(X[0], L, atol=tol) | np.isclose(X[1], L, atol=tol) | np.isclose(np.abs(X[2]), L, atol=tol))
    sym = (np.isclose(X[0], 0.0, atol=tol) & (comp == 0)) | (np.isclose(X[1], 0.0, atol=tol) & (comp == 1))
    depth = np.where(body == 1, X[2], -X[2])
    with np.errstate(invalid="ignore", divide="ignore"):  # the contact point itself is not prescribed
        u_r, u_d = boussinesq(F, E, NU, r, np.maximum(depth, 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        cos, sin = np.where(r > 0, X[0] / r, 0.0), np.where(r > 0, X[1] / r, 0.0)
    val = np.where(comp == 0, u_r * cos, np.where(comp == 1, u_r * sin, np.where(body == 1, u_d, -u_d)))
    dep_mask = outer | sym
    dep = np.flatnonzero(dep_mask)
    g = np.zeros(ndof)
    g[dep] = np.where(outer[dep], val[dep], 0.0)
    free = np.r_[np.flatnonzero(~dep_mask), delta_dof]
    col = np.full(ndof, -1)
    col[free] = np.arange(free.size)
    on_delta = dep[outer[dep] & (body[dep] == 1) & (comp[dep] == 2)]
    rows = np.r_[free, on_delta]
    cols = np.r_[np.arange(free.size), np.full(on_delta.size, col[delta_dof])]
    T = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(ndof, free.size))
    D = sp.csr_matrix((np.ones(on_delta.size), (np.searchsorted(dep, on_delta), np.full(on_delta.size, delta_dof))),
                      shape=(dep.size, ndof))
    return Constraints(ndof=ndof, dependent=dep, free=np.sort(free), T=T, g=g, relations=(dep, D, g[dep]))


def build(level: str = "default", penalty_factor: float = 100.0, F_max: float = max(LOADS_N), intorder: int = 2) -> HertzModel:
    """Mesh, assemble and pair the quarter model at refinement ``level`` for the load F_max (N)."""
    t0 = time.perf_counter()
    mesh, n_lower = make_mesh(level)
    t1 = time.perf_counter()
    basis = vector_basis(mesh, 2)
    K = assemble_stiffness(basis, E, NU)
    body = dof_body(basis, n_lower)
    tol = 1e-9 * L
    delta_dof = basis.N
    C = _far_field_constraints(basis, body, F_max, delta_dof, tol)
    f = np.zeros(basis.N + 1)
    f[delta_dof] = -F_max / 4.0
    bf = mesh.boundary_facets()
    fc = mesh.p[:, mesh.facets[:, bf]].mean(axis=1)
    upper_f = mesh.f2t[0, bf] >= n_lower
    interior = (fc[0] < L - tol) & (fc[1] < L - tol) & (fc[0] > tol) & (fc[1] > tol)
    slave = bf[upper_f & interior & (fc[2] < L - tol)]
    master = bf[~upper_f & interior & np.isclose(fc[2], 0.0, atol=tol)]
    eps = default_penalty(mesh, slave, E, penalty_factor)
    pair = pair_surfaces(basis, slave, master, penalty_n=eps, friction=0.0, name="sphere-block", ndof=basis.N + 1,
                         intorder=intorder)
    problem = ContactProblem(K=K, f=f, constraints=C, pairs=(pair,))
    return HertzModel(problem=problem, pair=pair, basis=basis, delta_dof=delta_dof, n_lower=n_lower,
                      assembly_s=time.perf_counter() - t1, mesh_s=t1 - t0)


def solve(model: HertzModel, loads=LOADS_N, **kwargs):
    """Solve for the loads (N, ascending, the last = F_max of the model) as load steps."""
    F_max = -4.0 * model.problem.f[model.delta_dof]
    # initial closure step: close the slave points nearest to touching (within 1e-12 m of the first)
    kwargs.setdefault("initial_closure", max(float(model.pair.g0.min()), 0.0) + 1e-12)
    return solve_contact(model.problem, [F / F_max for F in loads], **kwargs)


def evaluate(model: HertzModel, result, loads=LOADS_N, depths=None) -> list[dict]:
    """Per load: Hertz closed form vs FE approach (direct and depth extraction) and contact radius."""
    E_star = float(effective_modulus(E, NU, E, NU))
    X = model.basis.doflocs
    body = dof_body(model.basis, model.n_lower)
    on_axis = np.isclose(X[0], 0.0, atol=1e-12) & np.isclose(X[1], 0.0, atol=1e-12) & (np.arange(model.basis.N) % 3 == 2)
    if depths is None:  # axis nodes of both bodies between 3 and 8 contact radii (50 N) deep
        zs = X[2, on_axis & (body == 0)]
        a_max = hertz_point(max(loads), E_star, R).a
        depths = np.unique(np.round(-zs[(-zs >= 3 * a_max) & (-zs <= 8 * a_max)], 12))
    out = []
    r_pts = np.hypot(model.pair.points[:, 0], model.pair.points[:, 1])
    for F, step in zip(loads, result.steps):
        h = hertz_point(F, E_star, R)
        u = step.u
        delta = -u[model.delta_dof]
        ps = step.pairs[0]
        closed = ps.pressure > 0
        area = float(np.sum(model.pair.weights[closed]))
        a_area = np.sqrt(4.0 * area / np.pi)
        a_in = float(r_pts[closed].max()) if closed.any() else 0.0
        a_out = float(r_pts[~closed & (r_pts > a_in * 0.5)].min()) if (~closed).any() else np.inf
        ext = []
        for d in depths:
            up = np.flatnonzero(on_axis & (body == 1) & np.isclose(X[2], d, rtol=1e-6))
            lo = np.flatnonzero(on_axis & (body == 0) & np.isclose(X[2], -d, rtol=1e-6))
            if up.size and lo.size:
                approach = u[lo[0]] - u[up[0]]
                v = float(hertz_axis_displacement(d, h.a, h.p0, E, NU))
                ext.append({"depth_m": d, "delta_m": float(approach + 2.0 * v)})
        force = 4.0 * ps.force(model.pair)
        out.append({"force_N": F, "contact_force_N": force, "delta_m": float(delta), "delta_hertz_m": h.delta,
                    "delta_rel_error": float(abs(delta - h.delta) / h.delta), "a_m": a_in,
                    "a_hertz_m": h.a, "a_rel_error": float(abs(a_in - h.a) / h.a),
                    "a_area_m": float(a_area), "a_area_rel_error": float(abs(a_area - h.a) / h.a),
                    "a_bracket_m": [a_in, a_out], "p_max_Pa": float(ps.pressure.max()), "p0_hertz_Pa": h.p0,
                    "depth_extraction": ext, "iterations": step.iterations, "factorizations": step.factorizations,
                    "augmentations": step.augmentations})
    return out


def run(mesh: str = "default") -> CheckResult:
    t0 = time.perf_counter()
    model = build(mesh)
    res = solve(model)
    ev = evaluate(model, res)
    first = ev[0]
    return CheckResult(name=NAME, quantity="mutual approach at 15 N (m)", computed=first["delta_m"],
                       reference=first["delta_hertz_m"], dofs=int(model.basis.N + 1),
                       iterations=int(sum(res.iterations_per_step)), seconds=time.perf_counter() - t0,
                       detail={"loads": ev, "timings": res.timings, "solver": res.solver,
                               "slave_points": model.pair.n_points})
