"""Pin in a conforming bore with clearance, femcheck and CalculiX on one mesh.

Conformal contact, the situation of the universal-joint pins (not the joint FE model itself: a standalone
plane-strain slice). A steel pin, a tube r ∈ [R_IN, R_PIN], sits in a steel block with a bore of radius
R_PIN + CLEARANCE and outer radius R_OUT; half model (x ≥ 0), one element through the thickness T with
u_z = 0 everywhere (plane strain). The block's outer face is clamped; the pin's inner face translates rigidly
in −y by Δ (u_x = 0, u_y = −Δ: one extra unknown carrying −F/2 for the half model). The pin starts touching
the bore at its bottom line (shifted down by the clearance), so the initial gap is ≈ c (1 − cos θ).

There is no closed form used here (Persson's conformal solution needs the elastic pin on an elastic plate
with an infinite outer radius); the comparison is code against code on the same discrete problem: the pin
displacement Δ (m) and the contact half-angle from the nodal forces on the bore, θ_c = sqrt(2 Σ f θ² / Σ f)
(the rms angle of the contact force scaled by √2, which is θ_c for a uniform distribution; used only to compare
the two codes).
"""
from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

E, NU = 210e9, 0.3
R_IN, R_PIN, CLEARANCE, R_OUT, T = 0.5e-3, 2.0e-3, 10e-6, 6.0e-3, 0.25e-3
#: loads (N) on the full slice (the half model carries half)
LOADS_N = (100.0, 400.0)
#: (radial cells in the pin, radial cells in the block, cells over the half circle)
CELLS = (6, 8, 96)


def _half_annulus(r_in, r_out, nr, nth, y0=0.0):
    import skfem
    m = skfem.MeshTet.init_tensor(np.linspace(r_in, r_out, nr + 1), np.linspace(0.0, np.pi, nth + 1), np.array([0.0, T]))
    r, th, z = m.p
    p = np.vstack([r * np.sin(th), -r * np.cos(th) + y0, z])
    return skfem.MeshTet(np.ascontiguousarray(p), np.ascontiguousarray(m.t))


def make_mesh():
    """(mesh, n_lower): the block (lower, master) then the pin (slave), not merged."""
    from femcheck.fe.checks._graded_mesh import join
    npin, nblk, nth = CELLS
    block = _half_annulus(R_PIN + CLEARANCE, R_OUT, nblk, nth)
    pin = _half_annulus(R_IN, R_PIN, npin, nth, y0=-CLEARANCE)
    return join(block, pin)


def _on_circle(r, R):
    """r within the chord sag of the circle of radius R (P2 edge midpoints of the arc lie on the chords)."""
    return (r <= R + 1e-9 * R_OUT) & (r >= R * np.cos(np.pi / (2 * CELLS[2])) - 1e-9 * R_OUT)


def _node_sets(X, body):
    """Boolean masks over positions X (n, 3): symmetry plane, pin inner face, block outer face."""
    r_blk = np.hypot(X[:, 0], X[:, 1])
    r_pin = np.hypot(X[:, 0], X[:, 1] + CLEARANCE)
    sym = np.abs(X[:, 0]) < 1e-9 * R_OUT
    inner = (body == 1) & _on_circle(r_pin, R_IN)
    outer = (body == 0) & _on_circle(r_blk, R_OUT)
    return sym, inner, outer


def _surface_facets(mesh, n_lower):
    """(slave = pin outer face, master = bore face) boundary facets (all three vertices on the circle)."""
    tol = 1e-9 * R_OUT
    bf = mesh.boundary_facets()
    P = mesh.p[:, mesh.facets[:, bf]]  # (3, 3 vertices, nf)
    on_pin = np.all(np.abs(np.hypot(P[0], P[1] + CLEARANCE) - R_PIN) < tol, axis=0)
    on_bore = np.all(np.abs(np.hypot(P[0], P[1]) - (R_PIN + CLEARANCE)) < tol, axis=0)
    upper = mesh.f2t[0, bf] >= n_lower
    return bf[on_pin & upper], bf[on_bore & ~upper]


def contact_angle(basis, K, u, n_lower) -> tuple[float, float]:
    """(θ_c rad, Σ f over the half model N) from the bore-face nodal forces f = K u (see the module doc)."""
    from femcheck.fe.checks._graded_mesh import dof_body
    xd, yd = np.r_[basis.nodal_dofs[0], basis.edge_dofs[0]], np.r_[basis.nodal_dofs[1], basis.edge_dofs[1]]
    P = basis.doflocs[:, xd]
    body = dof_body(basis, n_lower)[xd]
    bore = (body == 0) & _on_circle(np.hypot(P[0], P[1]), R_PIN + CLEARANCE)
    f = K @ u[:basis.N]
    # force of the pin on the bore, along the outward bore radius (from the bore centre)
    th = np.arctan2(P[0, bore], -P[1, bore])
    fr = f[xd[bore]] * np.sin(th) - f[yd[bore]] * np.cos(th)
    total = -float(np.sum(f[yd[bore]]))  # the −y resultant on the bore = the load on the half model
    return float(np.sqrt(2.0 * np.sum(fr * th**2) / np.sum(fr))), total


def run_femcheck(penalty_factor: float = 100.0) -> dict:
    from femcheck.fe.constraints import Constraints
    from femcheck.fe.checks._graded_mesh import dof_body
    from femcheck.fe.contact.pairing import default_penalty, pair_surfaces
    from femcheck.fe.elasticity import assemble_stiffness, vector_basis
    from femcheck.fe.newton import ContactProblem, solve_contact

    t0 = time.perf_counter()
    mesh, n_lower = make_mesh()
    basis = vector_basis(mesh, 2)
    K = assemble_stiffness(basis, E, NU)
    N = basis.N
    ndof = N + 1
    delta = N
    X = basis.doflocs.T
    comp = np.arange(N) % 3
    body = dof_body(basis, n_lower)
    sym, inner, outer = _node_sets(X, body)
    dep_mask = (sym & (comp == 0)) | (comp == 2) | outer | (inner & (comp != 2))
    dep = np.flatnonzero(dep_mask)
    free = np.r_[np.flatnonzero(~dep_mask), delta]
    col = np.full(ndof, -1)
    col[free] = np.arange(free.size)
    tied = dep[inner[dep] & (comp[dep] == 1)]  # u_y = −Δ on the pin's inner face
    rows = np.r_[free, tied]
    cols = np.r_[np.arange(free.size), np.full(tied.size, col[delta])]
    vals = np.r_[np.ones(free.size), -np.ones(tied.size)]
    Tm = sp.csr_matrix((vals, (rows, cols)), shape=(ndof, free.size))
    D = sp.csr_matrix((-np.ones(tied.size), (np.searchsorted(dep, tied), np.full(tied.size, delta))), shape=(dep.size, ndof))
    C = Constraints(ndof=ndof, dependent=dep, free=np.sort(free), T=Tm, g=np.zeros(ndof), relations=(dep, D, np.zeros(dep.size)))
    F_max = max(LOADS_N)
    f = np.zeros(ndof)
    f[delta] = F_max / 2.0  # −F/2 along y = +F/2 on Δ (u_y = −Δ)
    slave, master = _surface_facets(mesh, n_lower)
    eps = default_penalty(mesh, slave, E, penalty_factor)
    pair = pair_surfaces(basis, slave, master, penalty_n=eps, friction=0.0, name="pin-bore", ndof=ndof, intorder=2)
    problem = ContactProblem(K=K, f=f, constraints=C, pairs=(pair,))
    res = solve_contact(problem, [F / F_max for F in LOADS_N], initial_closure=max(float(pair.g0.min()), 0.0) + 1e-12,
                        max_lowrank=1000)
    wall = time.perf_counter() - t0
    out = {"wall_s": wall, "dofs": int(ndof), "factorizations": int(res.timings["factorizations"]), "loads": []}
    for F, step in zip(LOADS_N, res.steps):
        th, total = contact_angle(basis, K, step.u, n_lower)
        out["loads"].append({"force_N": F, "delta_m": float(step.u[delta]), "theta_c_deg": float(np.degrees(th)),
                             "force_ratio": 2.0 * total / F, "iterations": int(step.iterations)})
    return out


def ccx_deck(penalty_factor: float = 100.0, overlap: float = 0.5e-6) -> dict:
    """CalculiX deck of the same half model (C3D10 on the same mesh); the pin starts ``overlap`` into the bore."""
    from femcheck.fe import calculix as cx

    mesh, n_lower = make_mesh()
    m10 = cx.tet10(mesh)
    X = m10.nodes.copy()
    nv_lower = int(mesh.t[:, :n_lower].max()) + 1
    vbody = (np.arange(m10.nv) >= nv_lower).astype(np.int8)
    body = np.r_[vbody, vbody[mesh.edges[0]]]
    sym, inner, outer = _node_sets(X, body)
    X[body == 1, 1] -= overlap
    slave, master = _surface_facets(mesh, n_lower)
    s_el, s_face = cx.facet_faces(mesh, m10, slave)
    m_el, m_face = cx.facet_faces(mesh, m10, master)
    h = R_PIN * np.pi / CELLS[2]
    ref = X.shape[0] + 1
    parts = ["*HEADING\nfemcheck pin in bore (half model, plane strain slice)\n",
             cx.deck_mesh(cx.Tet10(nodes=X, elements=m10.elements, nv=m10.nv)),
             f"*NODE, NSET=NREF\n{ref}, 0.0, 0.0, 0.0\n", cx.deck_material("STEEL", E, NU),
             cx.deck_surface("SPIN", s_el, s_face), cx.deck_surface("SBORE", m_el, m_face),
             "*EQUATION\n" + "".join(f"2\n{n + 1}, 2, 1.0, {ref}, 2, -1.0\n" for n in np.flatnonzero(inner)),
             "*BOUNDARY\n" + "".join(f"{n + 1}, 1, 3\n" for n in np.flatnonzero(outer))
             + "".join(f"{n + 1}, 1, 1\n" for n in np.flatnonzero((sym | inner) & ~outer))
             + "".join(f"{n + 1}, 3, 3\n" for n in np.flatnonzero(~outer)) + f"{ref}, 1, 1\n{ref}, 3, 3\n",
             "*SURFACE INTERACTION, NAME=SI\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n"
             f"{cx.NUM.format(penalty_factor * E / h)}\n",
             "*CONTACT PAIR, INTERACTION=SI, TYPE=SURFACE TO SURFACE\nSPIN, SBORE\n"]
    for F in LOADS_N:
        parts += ["*STEP, INC=200\n*STATIC\n1.0, 1.0, 1e-5, 1.0\n", f"*CLOAD\n{ref}, 2, {cx.NUM.format(-F / 2.0)}\n",
                  "*NODE PRINT, NSET=NREF\nU\n*NODE FILE\nU\n*END STEP\n"]
    return {"deck": "".join(parts), "mesh": mesh, "n_lower": n_lower, "mesh10": m10, "overlap_m": overlap}


def run_ccx(workdir=None) -> dict:
    import shutil
    import tempfile

    from femcheck.fe import calculix as cx
    from femcheck.fe.elasticity import assemble_stiffness, vector_basis

    d = ccx_deck()
    wd = workdir if workdir is not None else tempfile.mkdtemp(prefix="femcheck-ccx-pin-")
    try:
        res = cx.run(d["deck"], job="pin", workdir=wd)
        tables = cx.parse_dat(res.dat)
        disp = cx.parse_frd(res.frd, "DISP")
    finally:
        if workdir is None:
            shutil.rmtree(wd, ignore_errors=True)
    basis = vector_basis(d["mesh"], 2)
    K = assemble_stiffness(basis, E, NU)
    dofs = cx.node_dofs(basis, d["mesh10"])
    out = {"wall_s": res.wall_s, "dofs": 3 * d["mesh10"].nodes.shape[0], **cx.iterations(res.log), "loads": []}
    for k, F in enumerate(LOADS_N):
        ref = [tb for tb in tables if abs(tb["time"] - (k + 1)) < 1e-6 and tb["set"] == "NREF"][-1]["rows"]
        u = np.zeros(basis.N)
        for node, v in [c for c in disp if c[0] is not None and abs(c[0] - (k + 1)) < 1e-6][-1][1].items():
            if node - 1 < dofs.shape[0]:
                u[dofs[node - 1]] = v[:3]
        th, total = contact_angle(basis, K, u, d["n_lower"])
        out["loads"].append({"force_N": F, "delta_m": -float(ref[0, 2]) + d["overlap_m"], "theta_c_deg": float(np.degrees(th)),
                             "force_ratio": 2.0 * total / F})
    return out
