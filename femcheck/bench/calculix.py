"""Bench ``calculix``: femcheck and CalculiX side by side on the Hertz sphere-on-flat problem.

Problem (:mod:`femcheck.fe.checks.hertz_sphere`): identical steel (E = 210 GPa, ν = 0.3), sphere R = 5 mm on a
flat, F = 15 N and 50 N as two load steps, quarter model, against Johnson's closed form.

What each code solves, back to back in one run (figure prefixes in reports/bench/calculix.json):

- ``femcheck_``: femcheck's check as it stands (``geometry="half-space"``: two 1.5 mm boxes, the sphere profile
  in the initial gap, Boussinesq far field, augmented-Lagrangian penalty contact).
- ``femcheck_sphere_``: femcheck on the curved-body mesh (``geometry="sphere"``: the upper box's bottom face
  mapped onto the sphere).
- ``ccx_``: CalculiX on *the same curved-body mesh* (femcheck's vertices and P2 edge midpoints as C3D10 nodes,
  :mod:`femcheck.fe.calculix`), the same boundary conditions (symmetry planes; the Boussinesq field of F on the
  truncation faces; on the upper body's faces that field plus one rigid translation Δ carrying −F/4, written
  as ``*EQUATION`` u_z − u_z(REF) − u_z(AUX) = 0 with the AUX node prescribed to the Boussinesq value) and
  frictionless surface-to-surface penalty contact (``*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR``, slope
  ``CCX_PENALTY_FACTOR`` · E / h_core, the same factor as femcheck's penalty; CalculiX has no augmented-Lagrangian
  update, so its penetration p/slope stays in the approach). The sphere touches the block at one point, so under
  force control the upper body is free until contact closes; the deck starts it with an overlap of
  ``CCX_PRELOAD_OVERLAP_M`` (a rigid shift, added back: δ = −u_z(REF) + overlap).

So ``femcheck_sphere_`` and ``ccx_`` are the same discrete problem up to the contact formulation;
``femcheck_`` is the Hertz idealization.

Extraction. Approach δ = −Δ (both). Contact radius, three ways:

- ``radius_force``: the same extraction for both codes (:func:`force_moment_radius`): the block's top-face nodal
  forces f = K u (femcheck's stiffness, for CalculiX its displacement field read back) give
  a = sqrt(5/2 · Σ f r² / Σ f), the second pressure moment of the Hertz distribution. ``contact_force_ratio``
  = 4 Σ f / F checks the forces (1 within 1e-6 for both). For femcheck this equals its own ``a_fit``.
- ``radius`` (femcheck): the outermost closed slave integration point, femcheck's native radius.
- ``radius_cpress`` (CalculiX): the outermost slave node with CPRESS > 0, CalculiX's native nodal contact
  output. That nodal pressure is not a consistent field for quadratic faces (it integrates to 1.3–2.2 × F,
  ``cpress_force_ratio``; corner and midside nodes alternate), so it is shown for what a CalculiX user reads,
  not as the comparison.

Errors are signed, (FE − Hertz)/Hertz, %.

Pin in bore (``pin_`` figures, :mod:`femcheck.bench._pin_bore`): a steel pin in a conforming bore with radial
clearance, a plane-strain slice, the same mesh in both codes; pin displacement and contact half-angle compared
code against code (no closed form), run only when ccx is present.

Wall times are measured in the same process, one after the other, each on one thread (OPENBLAS_NUM_THREADS
for femcheck; OMP_NUM_THREADS = CCX_NPROC_EQUATION_SOLVER = 1 for ccx); the CalculiX time is the ccx process
alone (deck writing and result parsing excluded, reported apart). Without ``ccx`` on PATH the area reports
``ccx_status = "skipped: ccx not found ..."`` and the femcheck figures only.
"""
from __future__ import annotations

import shutil
import tempfile
import time

import numpy as np

AREA = "calculix"
#: mesh level of the side-by-side run (hertz_sphere.LEVELS)
LEVEL = "default"
#: CalculiX penalty slope = factor · E / (core cell size)
CCX_PENALTY_FACTOR = 100.0
#: initial overlap of the sphere into the block (m): a rigid shift, added back to the approach, that starts
#: CalculiX with a closed contact patch (about half the 15 N approach). Measured on a 6.6k-DOF level of this
#: model: 18 Newton iterations instead of 43 with a 10 nm overlap, approach changed by 0.006 % of δ.
CCX_PRELOAD_OVERLAP_M = 6e-7
#: block top-face nodes within this radius carry the contact forces of force_moment_radius (m; 3.4 a at 50 N)
FORCE_RADIUS_M = 0.4e-3
#: wall-clock limit of one ccx run (s)
CCX_TIMEOUT_S = 1800.0


# --------------------------------------------------------------------------------------------- the CalculiX deck

def hertz_deck(level: str = LEVEL, loads=None, penalty_factor: float | None = None, overlap: float | None = None) -> dict:
    """CalculiX deck of the curved-body Hertz quarter model on femcheck's mesh (see the module doc).

    Returns {"deck" (text), "ref_node" (1-based), "slave_faces" ((m, 6) 0-based nodes of the quadratic slave
    faces), "slave_nodes", "nodes" ((n, 3) m, as written, the upper body shifted by the overlap), "body" (0 block,
    1 sphere per node), "mesh" / "n_lower" / "mesh10" (femcheck's mesh and its C3D10 form), "slope_Pa_per_m",
    "loads", "overlap_m"}."""
    from femcheck.fe import calculix as cx
    from femcheck.fe.checks import hertz_sphere as hs
    from femcheck.fe.checks._hertz_model import contact_facets
    from femcheck.fe.contact.half_space import boussinesq

    loads = tuple(hs.LOADS_N if loads is None else loads)
    penalty_factor = CCX_PENALTY_FACTOR if penalty_factor is None else penalty_factor
    overlap = CCX_PRELOAD_OVERLAP_M if overlap is None else overlap
    E, NU, L = hs.E, hs.NU, hs.L
    mesh, n_lower = hs.make_mesh(level, "sphere")
    m10 = cx.tet10(mesh)
    X = m10.nodes
    nnode = X.shape[0]
    tol = 1e-9 * L
    # body of every node: vertices of the lower block come first (join does not merge coincident vertices)
    nv_lower = int(mesh.t[:, :n_lower].max()) + 1
    vbody = (np.arange(m10.nv) >= nv_lower).astype(np.int8)
    body = np.r_[vbody, vbody[mesh.edges[0]]]
    # the rigid shift: the upper body starts `overlap` into the block (δ = −u_z(REF) + overlap)
    X = X.copy()
    X[body == 1, 2] -= overlap
    r = np.hypot(X[:, 0], X[:, 1])
    outer = np.isclose(X[:, 0], L, atol=tol) | np.isclose(X[:, 1], L, atol=tol) | (np.abs(X[:, 2] + overlap * body) > L - tol)
    sym_x, sym_y = np.isclose(X[:, 0], 0.0, atol=tol), np.isclose(X[:, 1], 0.0, atol=tol)
    # contact surfaces (as hertz_sphere.build): slave = the upper body's curved bottom, master = the block's top
    slave, master = contact_facets(mesh, n_lower, tol)
    s_el, s_face = cx.facet_faces(mesh, m10, slave)
    m_el, m_face = cx.facet_faces(mesh, m10, master)
    face_nodes = []
    for e, f in zip(s_el, s_face):
        c = cx.C3D10_FACES[f - 1]
        mids = [4 + cx.C3D10_EDGES.index(tuple(sorted((c[i], c[(i + 1) % 3])))) for i in range(3)]
        face_nodes.append([m10.elements[e, k] for k in (*c, *mids)])
    slave_faces = np.array(face_nodes, dtype=np.int64)
    # penalty slope from the core cell (the contact zone's element size)
    h_core = hs.RHO_CORE / hs.LEVELS[level]
    slope = penalty_factor * E / h_core

    ref = nnode + 1                     # REF node: the rigid translation Δ of the upper far field
    up_outer = np.flatnonzero(outer & (body == 1))
    aux = {int(n): nnode + 2 + k for k, n in enumerate(up_outer)}  # one AUX node per upper far-field node

    def far_field(F):
        """(node, dof, value) of the prescribed far field for load F (N); AUX nodes carry the upper u_z."""
        with np.errstate(invalid="ignore", divide="ignore"):
            depth = np.where(body == 1, X[:, 2] + overlap, -X[:, 2])
            u_r, u_d = boussinesq(F, E, NU, r, np.maximum(depth, 0.0))
            cos = np.where(r > 0, X[:, 0] / r, 0.0)
            sin = np.where(r > 0, X[:, 1] / r, 0.0)
        rows = []
        for n in np.flatnonzero(outer):
            ux, uy = u_r[n] * cos[n], u_r[n] * sin[n]
            if sym_x[n]:
                ux = 0.0
            if sym_y[n]:
                uy = 0.0
            rows += [(n + 1, 1, ux), (n + 1, 2, uy)]
            if body[n] == 0:
                rows.append((n + 1, 3, -u_d[n]))
            else:
                rows.append((aux[int(n)], 3, u_d[n]))
        for n in np.flatnonzero(~outer & sym_x):
            rows.append((n + 1, 1, 0.0))
        for n in np.flatnonzero(~outer & sym_y):
            rows.append((n + 1, 2, 0.0))
        return rows

    parts = ["*HEADING\nfemcheck Hertz sphere on flat (quarter model, curved body), femcheck mesh level "
             f"{level}\n"]
    m10s = cx.Tet10(nodes=X, elements=m10.elements, nv=m10.nv)
    parts.append(cx.deck_mesh(m10s))
    parts.append("*NODE, NSET=NREF\n" + f"{ref}, 0.0, 0.0, {cx.NUM.format(float(L))}\n")
    parts.append("*NODE, NSET=NAUX\n" + "".join(
        f"{a}, {cx.NUM.format(X[n, 0])}, {cx.NUM.format(X[n, 1])}, {cx.NUM.format(X[n, 2] + 0.1 * L)}\n"
        for n, a in aux.items()))
    parts.append(cx.deck_material("STEEL", E, NU))
    parts.append(cx.deck_surface("SSLAVE", s_el, s_face))
    parts.append(cx.deck_surface("SMASTER", m_el, m_face))
    parts.append("*EQUATION\n" + "".join(f"3\n{n + 1}, 3, 1.0, {ref}, 3, -1.0, {a}, 3, -1.0\n" for n, a in aux.items()))
    parts.append("*SURFACE INTERACTION, NAME=SI\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n"
                 f"{cx.NUM.format(slope)}\n")
    parts.append("*CONTACT PAIR, INTERACTION=SI, TYPE=SURFACE TO SURFACE\nSSLAVE, SMASTER\n")
    for F in loads:
        parts.append("*STEP, INC=200\n*STATIC\n1.0, 1.0, 1e-5, 1.0\n")
        parts.append("*BOUNDARY\n" + "".join(f"{n}, {d}, {d}, {cx.NUM.format(float(v))}\n" for n, d, v in far_field(F)))
        parts.append("*CLOAD\n" + f"{ref}, 3, {cx.NUM.format(-F / 4.0)}\n")
        parts.append("*NODE PRINT, NSET=NREF\nU\n*NODE FILE\nU\n*CONTACT FILE\nCSTR\n*END STEP\n")
    return {"deck": "".join(parts), "ref_node": ref, "slave_faces": slave_faces, "slave_nodes": np.unique(slave_faces),
            "nodes": X, "body": body, "mesh": mesh, "n_lower": n_lower, "mesh10": m10, "slope_Pa_per_m": slope, "loads": loads,
            "overlap_m": overlap}


# ------------------------------------------------------------------------------------------------ extraction

def force_moment_radius(basis, K, u, n_lower: int, r_max: float = FORCE_RADIUS_M) -> tuple[float, float]:
    """Contact radius (m) from the contact forces on the flat block, the same extraction for both codes.

    The nodal forces f = K u of the lower body (femcheck's P2 stiffness ``K`` on ``basis``; for CalculiX its
    displacements on the same mesh) at the block's top-face nodes within ``r_max`` of the axis are the contact
    forces there (the face is free elsewhere). P2 interpolation reproduces r² = x² + y² exactly on the flat
    face, so Σ f_z r² / Σ f_z = ∫p r² dA / ∫p dA of the discrete traction, and for the Hertz pressure
    that is 2a²/5: a = sqrt(5/2 · Σ f_z r² / Σ f_z) (the moment recovery of hertz_sphere, applied to nodal
    forces instead of femcheck's Gauss-point pressures). Returns (a m, Σ f_z over the quarter N)."""
    from femcheck.fe.checks import hertz_sphere as hs
    from femcheck.fe.checks._graded_mesh import dof_body

    zd = np.r_[basis.nodal_dofs[2], basis.edge_dofs[2]]
    P = basis.doflocs[:, zd]
    body = dof_body(basis, n_lower)[zd]
    r = np.hypot(P[0], P[1])
    top = (body == 0) & (np.abs(P[2]) < 1e-9 * hs.L) & (r < r_max)
    fz = -(K @ u[:basis.N])[zd[top]]  # the force the sphere exerts on the block, −z: positive here
    total = float(fz.sum())
    return float(np.sqrt(2.5 * float(np.sum(fz * r[top] ** 2)) / total)), total


def run_femcheck(geometry: str, level: str = LEVEL) -> dict:
    """femcheck's Hertz model (hertz_sphere) for ``geometry``: per load the signed errors, plus time and counts."""
    from femcheck.fe.checks import hertz_sphere as hs

    t0 = time.perf_counter()
    model = hs.build(level, geometry=geometry)
    res = hs.solve(model)
    ev = hs.evaluate(model, res)
    wall = time.perf_counter() - t0
    out = {"wall_s": wall, "dofs": int(model.basis.N + 1), "factorizations": int(res.timings["factorizations"]),
           "solver": res.solver, "loads": []}
    K = model.problem.K
    for e, step in zip(ev, res.steps):
        a_f, fz = force_moment_radius(model.basis, K, step.u, model.n_lower)
        out["loads"].append({"force_N": e["force_N"], "delta_error": e["delta_error"], "a_error": e["a_error"],
                             "a_fit_error": e["a_fit_error"], "a_force_error": (a_f - e["a_hertz_m"]) / e["a_hertz_m"],
                             "force_ratio": 4.0 * fz / e["force_N"], "iterations": int(step.iterations)})
    return out


# ------------------------------------------------------------------------------------------ CalculiX results

#: 6-point (degree 4) rule on the reference triangle: (ξ, η), weights summing to 1/2
_A, _B = 0.445948490915965, 0.091576213509771
_TRI_QP = np.array([[_A, _A], [1 - 2 * _A, _A], [_A, 1 - 2 * _A], [_B, _B], [1 - 2 * _B, _B], [_B, 1 - 2 * _B]])
_TRI_W = 0.5 * np.r_[np.full(3, 0.223381589678011), np.full(3, 0.109951743655322)]


def _tri6(xi, eta):
    """Quadratic triangle shape functions (corners 1-3, midsides 1-2, 2-3, 3-1) and their derivatives."""
    l1, l2, l3 = 1 - xi - eta, xi, eta
    N = np.array([l1 * (2 * l1 - 1), l2 * (2 * l2 - 1), l3 * (2 * l3 - 1), 4 * l1 * l2, 4 * l2 * l3, 4 * l3 * l1])
    dxi = np.array([-(4 * l1 - 1), 4 * l2 - 1, 0.0, 4 * (l1 - l2), 4 * l3, -4 * l3])
    deta = np.array([-(4 * l1 - 1), 0.0, 4 * l3 - 1, -4 * l2, 4 * l2, 4 * (l1 - l3)])
    return N, dxi, deta


def surface_integral(nodes: np.ndarray, faces: np.ndarray, f_node: np.ndarray, weight=None) -> float:
    """∫ f dA over quadratic faces (m, 6) of nodal values f_node, optionally times weight(x) ((k, 3) -> (k,))."""
    total = 0.0
    for (xi, eta), w in zip(_TRI_QP, _TRI_W):
        N, dxi, deta = _tri6(xi, eta)
        P = nodes[faces]
        x = np.einsum("k,mkj->mj", N, P)
        dA = np.linalg.norm(np.cross(np.einsum("k,mkj->mj", dxi, P), np.einsum("k,mkj->mj", deta, P)), axis=1) * w
        f = f_node[faces] @ N
        total += float(np.sum(dA * f * (1.0 if weight is None else weight(x))))
    return total


def solve_ccx(level: str = LEVEL, workdir=None, timeout_s: float = CCX_TIMEOUT_S, keep: bool = False) -> dict:
    """Write, run and read the CalculiX Hertz model (:func:`hertz_deck`): per load the signed errors against
    Hertz, plus the ccx wall time, deck/parse times and iteration counts. The work directory is removed
    unless ``keep`` or ``workdir`` is given."""
    from femcheck.compliance.hertz_point_contact import effective_modulus
    from femcheck.fe import calculix as cx
    from femcheck.fe.checks import hertz_sphere as hs
    from femcheck.fe.contact.half_space import hertz_point

    t0 = time.perf_counter()
    d = hertz_deck(level)
    t_deck = time.perf_counter() - t0
    wd = workdir if workdir is not None else tempfile.mkdtemp(prefix="femcheck-ccx-hertz-")
    try:
        run = cx.run(d["deck"], job="hertz", workdir=wd, timeout_s=timeout_s)
        t1 = time.perf_counter()
        tables = cx.parse_dat(run.dat)
        contact = cx.parse_frd(run.frd, "CONTACT")
        disp = cx.parse_frd(run.frd, "DISP")
    finally:
        if workdir is None and not keep:
            shutil.rmtree(wd, ignore_errors=True)
    from femcheck.fe.elasticity import assemble_stiffness, vector_basis
    E_star = float(effective_modulus(hs.E, hs.NU, hs.E, hs.NU))
    X = d["nodes"]
    r_node = np.hypot(X[:, 0], X[:, 1])
    basis = vector_basis(d["mesh"], 2)
    K = assemble_stiffness(basis, hs.E, hs.NU)
    dofs = cx.node_dofs(basis, d["mesh10"])
    out = []
    for k, F in enumerate(d["loads"]):
        h = hertz_point(F, E_star, hs.R)
        at = [tb for tb in tables if abs(tb["time"] - (k + 1)) < 1e-6]
        ref = [tb for tb in at if tb["set"] == "NREF"][-1]["rows"]
        delta = -float(ref[0, 3]) + d["overlap_m"]
        u = np.zeros(basis.N)
        for node, v in [c for c in disp if c[0] is not None and abs(c[0] - (k + 1)) < 1e-6][-1][1].items():
            if node - 1 < X.shape[0]:
                u[dofs[node - 1]] = v[:3]
        a_f, fz = force_moment_radius(basis, K, u, d["n_lower"])
        vals = [c for c in contact if c[0] is not None and abs(c[0] - (k + 1)) < 1e-6][-1][1]
        p_node = np.zeros(X.shape[0])
        for node, v in vals.items():
            if node - 1 < X.shape[0] and len(v) >= 4:
                p_node[node - 1] = v[3]  # COPEN, CSLIP1, CSLIP2, CPRESS, CSHEAR1, CSHEAR2
        sn = d["slave_nodes"]
        closed = sn[p_node[sn] > 0]
        a_cpress = float(r_node[closed].max()) if closed.size else 0.0
        out.append({"force_N": F, "delta_m": delta, "delta_error": (delta - h.delta) / h.delta,
                    "a_force_m": a_f, "a_force_error": (a_f - h.a) / h.a, "force_ratio": 4.0 * fz / F,
                    "a_hertz_m": h.a, "a_cpress_m": a_cpress, "a_cpress_error": (a_cpress - h.a) / h.a,
                    "cpress_force_ratio": 4.0 * surface_integral(X, d["slave_faces"], p_node) / F,
                    "p_max_Pa": float(p_node.max()), "p0_hertz_Pa": h.p0})
    return {"loads": out, "wall_s": run.wall_s, "deck_s": t_deck, "parse_s": time.perf_counter() - t1,
            "dofs": 3 * X.shape[0], **cx.iterations(run.log), "slope_Pa_per_m": d["slope_Pa_per_m"]}


# ------------------------------------------------------------------------------------------------------ bench

def _pct(x) -> float:
    return round(100.0 * float(x), 3)


def run() -> dict:
    from femcheck.fe import calculix as cx

    out: dict = {"problem": "Hertz sphere on flat, steel, R 5 mm, quarter model", "level": LEVEL}
    for tag, geometry in (("femcheck", "half-space"), ("femcheck_sphere", "sphere")):
        r = run_femcheck(geometry)
        out[f"{tag}_geometry"] = geometry
        out[f"{tag}_dofs"] = r["dofs"]
        out[f"{tag}_solver"] = r["solver"]
        out[f"{tag}_factorizations"] = r["factorizations"]
        for e in r["loads"]:
            F = int(e["force_N"])
            out[f"{tag}_approach_error_pct_{F}N"] = _pct(e["delta_error"])
            out[f"{tag}_radius_error_pct_{F}N"] = _pct(e["a_error"])
            out[f"{tag}_radius_force_error_pct_{F}N"] = _pct(e["a_force_error"])
            out[f"{tag}_contact_force_ratio_{F}N"] = round(e["force_ratio"], 5)
            out[f"{tag}_radius_fit_error_pct_{F}N"] = _pct(e["a_fit_error"])
            out[f"{tag}_iterations_{F}N"] = e["iterations"]
        out[f"{tag}_wall_s"] = round(r["wall_s"], 3)
    exe = cx.ccx_executable()
    if exe is None:
        out["ccx_status"] = cx.SKIP_REASON
        return out
    out["ccx_status"] = "ran"
    out["ccx_version"] = cx.ccx_version(exe)
    out["ccx_threads"] = 1
    try:
        lin = cx.cantilever_cross_check()
        out["ccx_cantilever_max_rel_diff"] = float(f"{lin['max_rel_diff']:.3g}")
        c = solve_ccx()
    except cx.CcxError as e:
        out["ccx_status"] = f"failed: {str(e).splitlines()[0]}"
        return out
    out["ccx_geometry"] = "sphere (femcheck's curved-body mesh as C3D10)"
    out["ccx_dofs"] = c["dofs"]
    out["ccx_penalty_Pa_per_m"] = c["slope_Pa_per_m"]
    for e in c["loads"]:
        F = int(e["force_N"])
        out[f"ccx_approach_error_pct_{F}N"] = _pct(e["delta_error"])
        out[f"ccx_radius_force_error_pct_{F}N"] = _pct(e["a_force_error"])
        out[f"ccx_contact_force_ratio_{F}N"] = round(e["force_ratio"], 5)
        out[f"ccx_radius_cpress_error_pct_{F}N"] = _pct(e["a_cpress_error"])
        out[f"ccx_cpress_force_ratio_{F}N"] = round(e["cpress_force_ratio"], 4)
    out["ccx_increments"] = c["increments"]
    out["ccx_iterations"] = c["iterations"]
    out["ccx_wall_s"] = round(c["wall_s"], 3)
    out["ccx_deck_and_parse_s"] = round(c["deck_s"] + c["parse_s"], 3)
    out["wall_ratio_ccx_over_femcheck"] = round(c["wall_s"] / out["femcheck_wall_s"], 3)
    out["wall_ratio_ccx_over_femcheck_sphere"] = round(c["wall_s"] / out["femcheck_sphere_wall_s"], 3)
    out.update(run_pin())
    return {k: v.item() if isinstance(v, np.generic) else v for k, v in out.items()}  # JSON: no numpy scalars


def run_pin() -> dict:
    """The pin-in-bore slice (:mod:`femcheck.bench._pin_bore`), femcheck then CalculiX: code against code."""
    from femcheck.bench import _pin_bore as pb
    from femcheck.fe import calculix as cx

    out: dict = {"pin_problem": (f"steel pin R {1e3 * pb.R_PIN:g} mm in a bore with {1e6 * pb.CLEARANCE:g} um radial "
                                 f"clearance, plane-strain slice {1e3 * pb.T:g} mm, half model")}
    f = pb.run_femcheck()
    try:
        c = pb.run_ccx()
    except cx.CcxError as e:
        out["pin_ccx_status"] = f"failed: {str(e).splitlines()[0]}"
        c = None
    out["pin_dofs"] = int(f["dofs"])
    for k, e in enumerate(f["loads"]):
        F = int(e["force_N"])
        out[f"pin_femcheck_displacement_um_{F}N"] = round(1e6 * e["delta_m"], 5)
        out[f"pin_femcheck_contact_half_angle_deg_{F}N"] = round(e["theta_c_deg"], 3)
        out[f"pin_femcheck_iterations_{F}N"] = e["iterations"]
        if c is not None:
            ec = c["loads"][k]
            out[f"pin_ccx_displacement_um_{F}N"] = round(1e6 * ec["delta_m"], 5)
            out[f"pin_ccx_contact_half_angle_deg_{F}N"] = round(ec["theta_c_deg"], 3)
            out[f"pin_displacement_diff_pct_{F}N"] = _pct((e["delta_m"] - ec["delta_m"]) / ec["delta_m"])
            out[f"pin_contact_half_angle_diff_pct_{F}N"] = _pct((e["theta_c_deg"] - ec["theta_c_deg"]) / ec["theta_c_deg"])
            out[f"pin_ccx_contact_force_ratio_{F}N"] = round(ec["force_ratio"], 5)
    out["pin_femcheck_wall_s"] = round(f["wall_s"], 3)
    if c is not None:
        out["pin_ccx_iterations"] = c["iterations"]
        out["pin_ccx_wall_s"] = round(c["wall_s"], 3)
        out["pin_wall_ratio_ccx_over_femcheck"] = round(c["wall_s"] / f["wall_s"], 3)
    return out


def table(figures: dict) -> str:
    """Markdown side-by-side table: errors against Hertz (signed, %) at 15 / 50 N, wall time and ratio."""
    cols = [("femcheck", "femcheck half-space"), ("femcheck_sphere", "femcheck curved body")]
    if figures.get("ccx_status") == "ran":
        cols.append(("ccx", f"CalculiX {figures.get('ccx_version') or ''} (same curved-body mesh)".replace("  ", " ")))

    def pair(tag, what):
        vals = [figures.get(f"{tag}_{what}_{F}N") for F in (15, 50)]
        return " / ".join("—" if v is None else f"{v:+.2f} %" for v in vals)
    rows = ["| 15 N / 50 N | " + " | ".join(c[1] for c in cols) + " |", "|---" * (len(cols) + 1) + "|"]
    rows.append("| DOF | " + " | ".join(str(figures.get(f"{t}_dofs", "—")) for t, _ in cols) + " |")
    rows.append("| approach error | " + " | ".join(pair(t, "approach_error_pct") for t, _ in cols) + " |")
    rows.append("| radius error, contact-force moments (same extraction) | " + " | ".join(pair(t, "radius_force_error_pct") for t, _ in cols) + " |")
    rows.append("| radius error, outermost closed point (femcheck) / node CPRESS > 0 (ccx) | " + " | ".join(
        pair(t, "radius_cpress_error_pct" if t == "ccx" else "radius_error_pct") for t, _ in cols) + " |")
    rows.append("| radius error, pressure moments (femcheck) | " + " | ".join(
        "—" if t == "ccx" else pair(t, "radius_fit_error_pct") for t, _ in cols) + " |")
    rows.append("| wall time (s) | " + " | ".join(f"{figures.get(f'{t}_wall_s', float('nan')):.1f}" for t, _ in cols) + " |")
    if figures.get("ccx_status") == "ran":
        rows.append(f"\nccx / femcheck wall time: {figures['wall_ratio_ccx_over_femcheck']:.2f}× (half-space), "
                    f"{figures['wall_ratio_ccx_over_femcheck_sphere']:.2f}× (curved body); ccx "
                    f"{figures['ccx_increments']} increments, {figures['ccx_iterations']} iterations")
    else:
        rows.append(f"\nCalculiX: {figures.get('ccx_status')}")
    if "pin_ccx_wall_s" in figures:
        rows += ["", f"Pin in bore ({figures['pin_problem']}), {figures['pin_dofs']} DOF, code against code:", "",
                 "| load | Δ femcheck (µm) | Δ CalculiX (µm) | diff | θ_c femcheck (°) | θ_c CalculiX (°) | diff |",
                 "|---|---|---|---|---|---|---|"]
        for F in (int(k.rsplit("_", 1)[1][:-1]) for k in figures if k.startswith("pin_femcheck_displacement_um_")):
            rows.append(f"| {F} N | {figures[f'pin_femcheck_displacement_um_{F}N']:.4f} | {figures[f'pin_ccx_displacement_um_{F}N']:.4f} | "
                        f"{figures[f'pin_displacement_diff_pct_{F}N']:+.2f} % | {figures[f'pin_femcheck_contact_half_angle_deg_{F}N']:.2f} | "
                        f"{figures[f'pin_ccx_contact_half_angle_deg_{F}N']:.2f} | {figures[f'pin_contact_half_angle_diff_pct_{F}N']:+.2f} % |")
        rows.append(f"\nwall time: femcheck {figures['pin_femcheck_wall_s']:.1f} s, CalculiX {figures['pin_ccx_wall_s']:.1f} s "
                    f"({figures['pin_wall_ratio_ccx_over_femcheck']:.2f}×)")
    return "\n".join(rows)


if __name__ == "__main__":
    from femcheck.bench.__main__ import print_figures
    print_figures(run(), table)
