"""CalculiX (``ccx``) as an independent cross-check of femcheck's FE: decks from femcheck's own meshes, results back.

CalculiX is optional. :func:`ccx_executable` finds it at run time (``$FEMCHECK_CCX`` or ``ccx`` on PATH; Debian
and Ubuntu: ``apt-get install calculix-ccx``); callers skip with :data:`SKIP_REASON` when it returns None.

Mesh. A scikit-fem ``MeshTet`` becomes quadratic C3D10 tetrahedra (:func:`tet10`): the mesh vertices are nodes
1..nv, the edge midpoints (straight edges, as femcheck's P2 basis uses them) nodes nv+1..nv+ne in
``mesh.edges`` order. CalculiX's C3D10 numbering: corners 1–4 with positive volume ((x2−x1)×(x3−x1)·(x4−x1) > 0),
then the midpoints of edges 1-2, 2-3, 1-3, 1-4, 2-4, 3-4; faces S1 = 1-2-3, S2 = 1-4-2, S3 = 2-4-3, S4 = 3-4-1
(:func:`element_faces`). Both codes then discretize the same body with the same quadratic field: C3D10's
4-point rule integrates the straight-sided P2 stiffness exactly, as femcheck's degree-2 rule does, so on a
linear problem the two agree to round-off (tests/test_calculix.py). :func:`node_dofs` maps CalculiX nodes to
femcheck's vector DOFs (``basis.nodal_dofs`` / ``basis.edge_dofs``).

Running. :func:`run` writes ``<job>.inp`` into a temporary directory, runs ``ccx -i <job>`` with a timeout and
one solver thread unless told otherwise (``OMP_NUM_THREADS`` / ``CCX_NPROC_EQUATION_SOLVER``), and returns the
``.dat`` text, the ``.frd`` path (kept while the :class:`CcxRun` lives in its directory) and the wall time.
:func:`parse_dat` reads the ``*NODE PRINT`` / ``*EL PRINT`` / ``*CONTACT PRINT`` tables of the ``.dat`` file;
:func:`parse_frd` reads one nodal result block (``DISP``, ``CONTACT``, …) of the ``.frd`` file per step.
Units: SI, as femcheck (m, N, Pa).
"""
from __future__ import annotations

import dataclasses
import os
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

#: message used wherever a CalculiX comparison is skipped
SKIP_REASON = "skipped: ccx not found (CalculiX is optional; Debian/Ubuntu: apt-get install calculix-ccx)"

#: C3D10 midside nodes 5..10 as corner pairs (0-based local corners)
C3D10_EDGES = ((0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))
#: C3D10 faces S1..S4: local corner indices (the face's midside nodes follow from C3D10_EDGES)
C3D10_FACES = ((0, 1, 2), (0, 3, 1), (1, 3, 2), (2, 3, 0))


def ccx_executable() -> str | None:
    """Path of the CalculiX solver: ``$FEMCHECK_CCX`` when set, else ``ccx`` on PATH; None when absent."""
    env = os.environ.get("FEMCHECK_CCX")
    if env:
        return shutil.which(env)
    return shutil.which("ccx")


def ccx_version(exe: str | None = None) -> str | None:
    """CalculiX version string (e.g. ``"2.20"``), None when unknown."""
    exe = exe or ccx_executable()
    if not exe:
        return None
    try:
        out = subprocess.run([exe, "-v"], capture_output=True, text=True, timeout=30).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    m = re.search(r"Version\s+([0-9][0-9.]*)", out)
    return m.group(1) if m else None


# ----------------------------------------------------------------------------------------------- mesh

@dataclasses.dataclass(frozen=True)
class Tet10:
    """C3D10 mesh: node coordinates (n, 3) m, elements (nt, 10) 0-based node indices, vertex count nv."""

    nodes: np.ndarray
    elements: np.ndarray
    nv: int


def _edge_index(mesh, a, b) -> np.ndarray:
    """Index in ``mesh.edges`` of the edges with end vertices a, b (arrays)."""
    nv = mesh.p.shape[1]
    e = np.sort(mesh.edges, axis=0)
    keys = e[0].astype(np.int64) * nv + e[1]
    order = np.argsort(keys)
    q = np.minimum(a, b).astype(np.int64) * nv + np.maximum(a, b)
    pos = order[np.searchsorted(keys, q, sorter=order)]
    if not np.array_equal(keys[pos], q):
        raise ValueError("tet10: an element edge is missing from mesh.edges")
    return pos


def tet10(mesh) -> Tet10:
    """C3D10 nodes and elements of a scikit-fem tetrahedral mesh (see the module doc for the numbering)."""
    p, t = mesh.p, mesh.t.copy()
    a, b, c, d = (p[:, t[i]] for i in range(4))
    neg = np.einsum("ij,ij->j", np.cross(b - a, c - a, axis=0), d - a) < 0
    t[[1, 2]] = np.where(neg, t[[2, 1]], t[[1, 2]])
    nv = p.shape[1]
    mid = 0.5 * (p[:, mesh.edges[0]] + p[:, mesh.edges[1]])
    nodes = np.ascontiguousarray(np.hstack([p, mid]).T)
    el = np.empty((t.shape[1], 10), dtype=np.int64)
    el[:, :4] = t.T
    for k, (i, j) in enumerate(C3D10_EDGES):
        el[:, 4 + k] = nv + _edge_index(mesh, t[i], t[j])
    return Tet10(nodes=nodes, elements=el, nv=nv)


def node_dofs(basis, mesh10: Tet10) -> np.ndarray:
    """(n_nodes, 3) femcheck vector-basis DOF of every C3D10 node and component (P2 vector basis)."""
    return np.ascontiguousarray(np.vstack([basis.nodal_dofs.T, basis.edge_dofs.T]))


def element_faces(mesh10: Tet10, facets_vertices: np.ndarray, elements: np.ndarray) -> np.ndarray:
    """Face number 1..4 of each boundary facet (3, m vertex indices) on its element (m,) (0-based)."""
    corners = mesh10.elements[elements, :4]  # (m, 4)
    fv = np.sort(facets_vertices.T, axis=1)
    out = np.zeros(elements.size, dtype=np.int64)
    for k, face in enumerate(C3D10_FACES):
        match = np.all(np.sort(corners[:, list(face)], axis=1) == fv, axis=1)
        out[match] = k + 1
    if np.any(out == 0):
        raise ValueError("element_faces: a facet is not a face of its element")
    return out


def facet_faces(mesh, mesh10: Tet10, facets) -> tuple[np.ndarray, np.ndarray]:
    """(elements 0-based, face numbers 1..4) of the boundary facets ``facets`` (indices into mesh.facets)."""
    facets = np.asarray(facets, dtype=np.int64)
    el = mesh.f2t[0, facets]
    return el, element_faces(mesh10, mesh.facets[:, facets], el)


# ----------------------------------------------------------------------------------------------- deck

def _lines(rows, per_line: int = 8) -> str:
    rows = [str(r) for r in rows]
    return "\n".join(", ".join(rows[i:i + per_line]) for i in range(0, len(rows), per_line)) + "\n"


#: CalculiX reads at most 20 characters per field: 13 significant digits (``-1.234567890123e-05``, 19 characters)
NUM = "{:.12e}"


def deck_mesh(mesh10: Tet10, elset: str = "EALL", elements=None) -> str:
    """``*NODE`` and ``*ELEMENT, TYPE=C3D10`` blocks (1-based numbers); ``elements`` selects rows (default all)."""
    out = ["*NODE, NSET=NALL\n"]
    out += [f"{i + 1}, {NUM.format(x)}, {NUM.format(y)}, {NUM.format(z)}\n" for i, (x, y, z) in enumerate(mesh10.nodes)]
    idx = np.arange(mesh10.elements.shape[0]) if elements is None else np.asarray(elements)
    out.append(f"*ELEMENT, TYPE=C3D10, ELSET={elset}\n")
    for e in idx:
        out.append(f"{e + 1}, " + ", ".join(str(n + 1) for n in mesh10.elements[e]) + "\n")
    return "".join(out)


def deck_nset(name: str, nodes) -> str:
    """``*NSET`` of 0-based node indices."""
    return f"*NSET, NSET={name}\n" + _lines(np.asarray(nodes, dtype=np.int64) + 1, 16)


def deck_surface(name: str, elements, faces) -> str:
    """Element-face ``*SURFACE`` (0-based elements, faces 1..4)."""
    return f"*SURFACE, NAME={name}, TYPE=ELEMENT\n" + "".join(f"{e + 1}, S{f}\n" for e, f in zip(elements, faces))


def deck_material(name: str, E: float, nu: float, elset: str = "EALL") -> str:
    return (f"*MATERIAL, NAME={name}\n*ELASTIC\n{NUM.format(E)}, {nu}\n"
            f"*SOLID SECTION, ELSET={elset}, MATERIAL={name}\n")


# ----------------------------------------------------------------------------------------------- run

@dataclasses.dataclass
class CcxRun:
    """One finished CalculiX job: its directory, .dat text, wall time (s), return code and log."""

    workdir: Path
    job: str
    dat: str
    wall_s: float
    returncode: int
    log: str

    @property
    def frd(self) -> Path:
        return self.workdir / f"{self.job}.frd"

    def ok(self) -> bool:
        return self.returncode == 0 and "*ERROR" not in self.log


class CcxError(RuntimeError):
    """CalculiX failed or timed out; the message carries the end of its log."""


def run(deck: str, job: str = "femcheck", workdir: str | Path | None = None, timeout_s: float = 900.0,
        threads: int = 1, exe: str | None = None) -> CcxRun:
    """Run CalculiX on ``deck`` in ``workdir`` (a new temporary directory when None, left for the caller).

    ``threads`` sets OMP_NUM_THREADS and CCX_NPROC_EQUATION_SOLVER (1 by default: a like-for-like comparison
    with femcheck run on one BLAS thread). Raises :class:`CcxError` on a non-zero exit, ``*ERROR`` in the log,
    or a timeout. The wall time covers the ccx process only (deck writing excluded).
    """
    exe = exe or ccx_executable()
    if not exe:
        raise CcxError(SKIP_REASON)
    wd = Path(workdir) if workdir is not None else Path(tempfile.mkdtemp(prefix="femcheck-ccx-"))
    wd.mkdir(parents=True, exist_ok=True)
    (wd / f"{job}.inp").write_text(deck)
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), CCX_NPROC_EQUATION_SOLVER=str(threads),
               CCX_NPROC_RESULTS=str(threads))
    t0 = time.perf_counter()
    try:
        proc = subprocess.run([exe, "-i", job], cwd=wd, capture_output=True, text=True, timeout=timeout_s, env=env)
    except subprocess.TimeoutExpired as e:
        raise CcxError(f"ccx ran past {timeout_s:.0f} s in {wd}") from e
    wall = time.perf_counter() - t0
    log = proc.stdout + proc.stderr
    dat_path = wd / f"{job}.dat"
    res = CcxRun(workdir=wd, job=job, dat=dat_path.read_text() if dat_path.exists() else "", wall_s=wall,
                 returncode=proc.returncode, log=log)
    if not res.ok():
        tail = "\n".join(log.strip().splitlines()[-15:])
        raise CcxError(f"ccx failed (exit {proc.returncode}) in {wd}:\n{tail}")
    return res


def iterations(log: str) -> dict:
    """Counts from the ccx log: ``increments`` and ``iterations`` (Newton iterations, all steps)."""
    return {"increments": len(re.findall(r"^\s*increment\s+\d+\s+attempt", log, flags=re.M)),
            "iterations": len(re.findall(r"^\s*iteration\s+\d+", log, flags=re.M))}


# ----------------------------------------------------------------------------------------------- results

_FLOAT = r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[EeDd][-+]?\d+)?"


def parse_dat(text: str) -> list[dict]:
    """Tables of a CalculiX ``.dat`` file: [{"title", "set", "time", "rows": (n, k) float array}], in file order.

    A table starts with a header line such as ``displacements (vx,vy,vz) for set NTIP and time 0.1E+01``; its
    rows are the following numeric lines (the first column is the node or element number)."""
    tables: list[dict] = []
    cur = None
    head = re.compile(r"^\s*(?P<title>.+?)\s+(?:for set|for all contact elements)\s*(?P<set>\S*)\s+and time\s+(?P<time>" + _FLOAT + r")")
    for line in text.splitlines():
        m = head.match(line)
        if m:
            cur = {"title": m.group("title").strip(), "set": m.group("set"), "time": float(m.group("time")), "rows": []}
            tables.append(cur)
            continue
        s = line.strip()
        if not s:
            continue
        if cur is not None and re.fullmatch(r"(?:" + _FLOAT + r"\s*)+", s):
            cur["rows"].append([float(v) for v in s.split()])
        elif cur is not None and cur["rows"]:
            cur = None
    for tb in tables:
        width = max((len(r) for r in tb["rows"]), default=0)
        tb["rows"] = np.array([r + [np.nan] * (width - len(r)) for r in tb["rows"]], dtype=float).reshape(-1, width)
    return tables


def parse_frd(path: str | Path, block: str) -> list[tuple[float, dict[int, np.ndarray]]]:
    """Nodal result block ``block`` (``DISP``, ``STRESS``, ``CONTACT``, …) of a ``.frd`` file, per output step:
    [(time, {node: values})]. Values are the block's first-line components (format 12 characters each)."""
    out: list[tuple[float, dict[int, np.ndarray]]] = []
    t_cur = None
    vals: dict[int, np.ndarray] | None = None
    with open(path) as fh:
        for line in fh:
            if line.startswith("    1PSTEP"):
                continue
            if line.startswith("  100C"):
                # "  100CL  101 0.100000000E+01 ..." : the step time follows the record key
                try:
                    t_cur = float(line[12:24])
                except ValueError:
                    t_cur = None
                vals = None
                continue
            if line.startswith(" -4"):
                name = line[5:13].strip()
                vals = {} if name == block else None
                if vals is not None:
                    out.append((t_cur, vals))
                continue
            if vals is None:
                continue
            if line.startswith(" -1"):
                node = int(line[3:13])
                body = line[13:].rstrip("\n")
                nums = [float(body[i:i + 12]) for i in range(0, len(body) - len(body) % 12, 12) if body[i:i + 12].strip()]
                vals[node] = np.array(nums)
            elif line.startswith(" -3"):
                vals = None
    return out


# ------------------------------------------------------------------------------------- linear cross-check

def cantilever_cross_check(nx: int = 10, ny: int = 2, workdir=None) -> dict:
    """The steel cantilever of ``femcheck.fe.checks.cantilever_solid`` (200 × 20 × 20 mm, P2 tets, beam-theory
    root support, 1 kN tip shear as consistent nodal forces) solved by femcheck and by CalculiX on one mesh.

    Same mesh, element, support and nodal loads, so the two displacement fields must agree to round-off plus
    the 7 significant digits of ccx's ``.dat`` print: returns {"max_abs_diff_m", "max_abs_u_m",
    "max_rel_diff" (of max |u|), "tip_femcheck_m", "tip_ccx_m" (mean u_y over the tip-face nodes),
    "dofs", "ccx_wall_s"}. Raises :class:`CcxError` when ccx is missing or fails.
    """
    import skfem

    from femcheck.fe import constraints
    from femcheck.fe.checks import cantilever_solid as cs
    from femcheck.fe.elasticity import assemble_stiffness, assemble_traction, vector_basis
    from femcheck.fe.linear_solver import factorize

    E, nu, L, H, B, P = cs.E, cs.NU, cs.L, cs.H, cs.B, cs.P
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, L, nx + 1), np.linspace(0, H, ny + 1), np.linspace(0, B, ny + 1))
    basis = vector_basis(mesh, 2)
    K = assemble_stiffness(basis, E, nu)
    tip = skfem.FacetBasis(mesh, basis.elem, facets=mesh.facets_satisfying(lambda x: np.isclose(x[0], L)), intorder=4)
    f = assemble_traction(tip, [0.0, P / (H * B), 0.0])
    m10 = tet10(mesh)
    nd = node_dofs(basis, m10)
    X = m10.nodes
    root = np.isclose(X[:, 0], 0.0)
    fix = [(np.flatnonzero(root), 0), (np.flatnonzero(root & np.isclose(X[:, 1], H / 2)), 1),
           (np.flatnonzero(root & np.isclose(X[:, 2], B / 2)), 2)]
    c = constraints.clamp(basis.N, np.concatenate([nd[n, k] for n, k in fix]))
    u = c.expand(factorize(c.reduce_matrix(K)).solve(c.reduce_vector(f)))
    Fn = f[nd]
    Fn[np.abs(Fn) < 1e-12 * np.abs(Fn).max()] = 0.0  # round-off on the corner nodes (P2: no corner load)
    deck = ["*HEADING\nfemcheck cantilever cross-check\n", deck_mesh(m10), deck_material("STEEL", E, nu), "*BOUNDARY\n"]
    deck += [f"{n + 1}, {k + 1}, {k + 1}\n" for nodes, k in fix for n in nodes]
    deck.append("*STEP\n*STATIC\n*CLOAD\n")
    deck += [f"{n + 1}, {k + 1}, {NUM.format(Fn[n, k])}\n" for n, k in zip(*np.nonzero(Fn))]
    deck.append("*NODE PRINT, NSET=NALL\nU\n*END STEP\n")
    wd = workdir if workdir is not None else tempfile.mkdtemp(prefix="femcheck-ccx-cantilever-")
    try:
        res = run("".join(deck), job="cantilever", workdir=wd)
    finally:
        if workdir is None:
            shutil.rmtree(wd, ignore_errors=True)
    rows = [tb for tb in parse_dat(res.dat) if tb["title"].startswith("displacements")][-1]["rows"]
    uc = np.zeros_like(X)
    uc[rows[:, 0].astype(int) - 1] = rows[:, 1:4]
    uf = u[nd]
    tipn = np.isclose(X[:, 0], L)
    diff = float(np.abs(uc - uf).max())
    return {"max_abs_diff_m": diff, "max_abs_u_m": float(np.abs(uf).max()), "max_rel_diff": diff / float(np.abs(uf).max()),
            "tip_femcheck_m": float(uf[tipn, 1].mean()), "tip_ccx_m": float(uc[tipn, 1].mean()), "dofs": int(basis.N),
            "ccx_wall_s": res.wall_s}
