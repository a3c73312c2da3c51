"""Dense Schur complement of a sparse symmetric matrix onto a small index set.

    S = K_rr − K_ri K_ii⁻¹ K_ir        (K: n x n sparse symmetric, r: the n_r retained indices)

:func:`schur_complement` asks MKL PARDISO for it during the factorization (``iparm[35] = 1``, the
retained rows marked in ``perm``): the elimination of the interior stops at the retained block, whose
dense update *is* S, so no right-hand sides are back-substituted at all. K_ii must be nonsingular; K_rr (and
S) may be singular (floating bodies held only by their retained contact DOFs).

:func:`condense` returns S together with the interior extension q_i = −K_ii⁻¹ K_ir u_r of a retained
displacement (the recovery after a condensed contact solve) from the *same* factorization: PARDISO keeps
its partial factorization LDLᵀ of K_ii and back-substitutes [0; u_r] (phase 333: the backward step with the
retained part fixed at u_r gives x_i = −L_iiᵀ⁻¹ L_riᵀ u_r = −K_ii⁻¹ K_ir u_r).

Without MKL (or where PARDISO fails) the condensation goes body by body: K_ii is block diagonal, one block per
body (the bodies meet only at retained DOFs), so S = K_rr − Σ_b K_rb K_bb⁻¹ K_br and only one body's factor is
in memory at a time. Each body's S_b comes from CHOLMOD's supernodal Cholesky (cvxopt) in the same way as
PARDISO's: the body's interior is ordered first (METIS nested dissection where pymetis is installed, else AMD:
:func:`fill_reducing_order`) and its retained DOFs last, so the trailing block of the factor is the Cholesky
factor of the Schur complement (George & Liu 1981, §2.3):

    P K_δ Pᵀ = L Lᵀ,  L = [[L_ii, 0], [L_ri, L_rr]]  ⇒  K_δ,rr − K_ri K_ii⁻¹ K_ir = L_rr L_rrᵀ,

where K_δ = K + δ E_r adds δ to the retained diagonal only. S itself may be singular (floating bodies),
S + δ I is positive definite for any δ > 0, and S = L_rr L_rrᵀ − δ I exactly (S is linear in K_rr);
δ is the mean retained diagonal, so the subtraction loses no more than round-off of S's own scale. L_rr is
read in place from CHOLMOD's supernodal arrays (:func:`_supernodal_trailing_block`, every field checked), and the
same factor then serves the extension (:class:`_FactorInterior`); where the factor's layout is not the one known,
cvxopt's copy of the whole factor gives L_rr and K_ii is factorized once more for the extension.

Memory: before factorizing, the factor's nonzeros are counted exactly from the elimination tree
(:func:`factor_nonzeros`); a body whose partial factor would exceed the budget (``$FEMCHECK_SCHUR_MEMORY_GB``,
default :data:`DEFAULT_MEMORY_GB`) is condensed by back-substitution instead: its K_ii factorized once and the
retained columns solved in blocks sized to what the budget leaves beside that factor (:func:`_block_columns`).
``FEMCHECK_SCHUR_METHOD=blockwise`` forces the back-substitution for every body, ``cholmod`` (the default) the
partial factorization where it fits.

Measured, no MKL, the matrices of the joints' coarse level (what ``femcheck verify`` condenses), one core at load
average 9–12, :func:`condense` wall time and peak resident memory of the process (matrix loaded first):

    universal (234,510 unknowns, 2,970 retained, 5 bodies): METIS 39.3 s, 2.09 GB; AMD 54.4 s, 2.98 GB
                (all at once with AMD and cvxopt's copy of the factor, before: 118.6 s, 6.89 GB; PARDISO 37.3 s, 2.13 GB)
    spherical  (92,361 unknowns, 2,226 retained, 2 bodies): METIS 14.3 s, 1.15 GB; AMD 21.9 s, 1.47 GB
                (before: 33.5 s, 2.74 GB; PARDISO 6.4 s, 0.93 GB)

S agrees with PARDISO's to 9e-14 (universal) and 2.5e-13 (spherical) of max |S|; the extension to 2e-11.
"""
from __future__ import annotations

import ctypes
import functools
import logging
import os
import time

import numpy as np
import scipy.sparse as sp

log = logging.getLogger(__name__)

#: environment variable: gigabytes that one condensation without MKL may hold for a body's factor and its blocks
MEMORY_VAR = "FEMCHECK_SCHUR_MEMORY_GB"
#: its default: the universal joint's largest body at the coarse level (the level ``femcheck verify`` uses, 86 M
#: nonzeros in L by nested dissection, 153 M by AMD) needs 1.4 and 2.4 GB, so it fits with either order, and the
#: 8 GB peak of the whole verify run leaves room beside it for the assembled meshes and the kept models
DEFAULT_MEMORY_GB = 4.0
#: resident bytes per nonzero of L during a partial factorization read in place: CHOLMOD's supernodal values
#: (8 B) with their padding and the assembly's transients (measured 14–15 B per counted nonzero: module doc)
BYTES_PER_FACTOR_NONZERO = 16
#: the same where the factor can only be copied out (cvxopt's ``getfactor``): the supernodal factor and its
#: simplicial copy (8 B value + 8 B row index) at once (measured 31 B per nonzero: module doc)
BYTES_PER_COPIED_NONZERO = 32
#: bounds of the retained columns back-substituted at once on the blockwise path
MIN_BLOCK, MAX_BLOCK = 16, 4096


def schur_complement(K, r: np.ndarray, *, method: str = "auto") -> np.ndarray:
    """(n_r, n_r) dense S of symmetric sparse ``K`` onto the sorted indices ``r`` (module doc).

    method: "auto" (PARDISO, else the fallback), "pardiso", "blockwise"."""
    c = condense(K, r, method=method)
    S = c.S
    c.free()
    return S


class SchurCondensation:
    """S = K_rr − K_ri K_ii⁻¹ K_ir (``S``, (n_r, n_r) dense) and the interior extension of a retained
    displacement from the same factorization (:meth:`extend`). ``method`` "pardiso" | "cholmod" (every body by
    partial factorization) | "blockwise" (some body back-substituted); ``factorizations`` made (PARDISO: 1, else
    one per body touching r, two where CHOLMOD's factor had to be copied out); ``seconds`` wall time of S."""

    def __init__(self, K, r, S, method: str, factorizations: int, seconds: float, extend_fn, free_fn=None):
        self.n = K.shape[0]
        self.r = r
        self.S = S
        self.method = method
        self.factorizations = factorizations
        self.seconds = seconds
        self._extend = extend_fn
        self._free = free_fn

    def extend(self, u_r) -> np.ndarray:
        """Full displacement q (n,) with q_r = u_r and K_ii q_i = −K_ir u_r (units of u_r)."""
        u_r = np.asarray(u_r, dtype=np.float64)
        if u_r.shape != (self.r.size,):
            raise ValueError(f"retained displacement has shape {u_r.shape}; expected ({self.r.size},)")
        if self._extend is None:
            raise RuntimeError("the factorization of this Schur condensation was released (free())")
        q = self._extend(u_r)
        q[self.r] = u_r
        return q

    def free(self) -> None:
        """Release the factorization (S stays)."""
        if self._free is not None:
            self._free()
        self._free = self._extend = None

    def __del__(self):
        try:
            self.free()
        except Exception:  # interpreter shutdown
            pass


def condense(K, r: np.ndarray, *, method: str = "auto") -> SchurCondensation:
    """S of symmetric sparse ``K`` onto the sorted indices ``r`` with its interior extension (module doc).

    method: "auto" (PARDISO, else CHOLMOD's partial factorization, else blockwise), "pardiso",
    "cholmod", "blockwise"."""
    K = sp.csr_matrix(K, dtype=np.float64)
    r = np.asarray(r, dtype=np.int64)
    if method not in ("auto", "pardiso", "cholmod", "blockwise"):
        raise ValueError(f"Schur complement method = {method!r}; expected auto, pardiso, cholmod or blockwise")
    t0 = time.perf_counter()
    if method == "auto":
        from femcheck.fe.linear_solver import pardiso_available, preferred
        if preferred() not in ("auto", "pardiso") or not pardiso_available():
            # the user's non-MKL choice, or no MKL: body by body, by CHOLMOD's partial factorization where the
            # factor fits the memory budget, else blockwise (module doc); FEMCHECK_SCHUR_METHOD forces one
            choice = os.environ.get("FEMCHECK_SCHUR_METHOD", "auto").strip().lower()
            if choice not in ("auto", "blockwise", "cholmod"):
                from femcheck.errors import FemcheckError
                raise FemcheckError(f"FEMCHECK_SCHUR_METHOD={choice!r}: expected auto, blockwise or cholmod")
            method = "blockwise" if choice == "blockwise" else "cholmod"
    if method in ("auto", "pardiso"):
        try:
            S, ext, fre = _pardiso_schur(K, r)
            dt = time.perf_counter() - t0
            log.info("Schur complement %d -> %d with PARDISO in %.2f s", K.shape[0], r.size, dt)
            return SchurCondensation(K, r, S, "pardiso", 1, dt, ext, fre)
        except (ImportError, OSError, RuntimeError) as exc:
            if method == "pardiso":
                raise
            log.info("PARDISO Schur complement unavailable (%s); CHOLMOD or blockwise", exc)
            method = "cholmod"
    memory_budget()   # a bad $FEMCHECK_SCHUR_MEMORY_GB is named before any work
    S, ext, nfac, npartial, nbodies = _nonmkl_schur(K, r, "cholmod" if method == "cholmod" else "blockwise")
    dt = time.perf_counter() - t0
    # "cholmod" when every body took the partial factorization, "blockwise" when one was back-substituted
    name = "cholmod" if method == "cholmod" and npartial == nbodies else "blockwise"
    log.info("Schur complement %d -> %d (%s, %d factorizations) in %.2f s", K.shape[0], r.size, name, nfac, dt)
    return SchurCondensation(K, r, S, name, nfac, dt, ext)


def _pardiso_schur(K, r):
    import pypardiso

    from femcheck.fe.linear_solver import pardiso_available
    pardiso_available()   # records MKL's path once: a new solver does not search the environment for it
    n, ns = K.shape[0], r.size
    solver = pypardiso.PyPardisoSolver(mtype=-2)  # real symmetric indefinite: S may be singular
    A = sp.triu(K, format="csr")
    A.sort_indices()
    perm = np.zeros(n, np.int32)
    perm[r] = 1
    iparm = np.zeros(64, np.int32)
    iparm[0] = 1    # iparm set by the caller
    iparm[1] = 2    # nested dissection (METIS)
    iparm[9] = 8    # pivot perturbation 1e-8
    iparm[34] = 1   # zero-based ia/ja
    iparm[35] = 1   # Schur complement of the perm-marked rows, returned dense in x
    ia, ja = A.indptr.astype(np.int32), A.indices.astype(np.int32)
    x = np.zeros(ns * ns)
    b = np.zeros(max(n, ns * ns))
    err = ctypes.c_int32(0)
    P, D = ctypes.POINTER(ctypes.c_int32), ctypes.POINTER(ctypes.c_double)

    def call(phase, b, x):
        solver._mkl_pardiso(solver.pt.ctypes.data_as(ctypes.POINTER(solver._pt_type[0])),
                            ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(1)),
                            ctypes.byref(ctypes.c_int32(-2)), ctypes.byref(ctypes.c_int32(phase)),
                            ctypes.byref(ctypes.c_int32(n)), A.data.ctypes.data_as(D), ia.ctypes.data_as(P),
                            ja.ctypes.data_as(P), perm.ctypes.data_as(P), ctypes.byref(ctypes.c_int32(1)),
                            iparm.ctypes.data_as(P), ctypes.byref(ctypes.c_int32(0)), b.ctypes.data_as(D),
                            x.ctypes.data_as(D), ctypes.byref(err))
        return err.value

    code = call(12, b, x)
    if code != 0:
        call(-1, b, x)  # release PARDISO's memory
        raise RuntimeError(f"PARDISO Schur complement: error {code}")
    S = x.reshape(ns, ns)
    S = 0.5 * (S + S.T)
    del b, x

    def extend(u_r):
        # backward substitution of [0; u_r] through the partial factorization: x_i = −K_ii⁻¹ K_ir u_r
        z = np.zeros(n)
        z[r] = u_r
        q = np.zeros(n)
        code = call(333, z, q)
        if code != 0:
            raise RuntimeError(f"PARDISO interior back-substitution: error {code}")
        return q

    def free():
        call(-1, np.zeros(1), np.zeros(1))

    return S, extend, free


def memory_budget() -> float:
    """Bytes one condensation without MKL may hold for a body's factor and its blocks: ``$FEMCHECK_SCHUR_MEMORY_GB``
    (gigabytes, 10⁹ B), else :data:`DEFAULT_MEMORY_GB`. Raises :class:`femcheck.errors.FemcheckError` (one line, naming
    the variable) for anything but a positive number."""
    raw = os.environ.get(MEMORY_VAR, "").strip()
    if not raw:
        return DEFAULT_MEMORY_GB * 1e9
    try:
        gb = float(raw)
    except ValueError:
        gb = float("nan")
    if not (np.isfinite(gb) and gb > 0):
        from femcheck.errors import FemcheckError
        raise FemcheckError(f"{MEMORY_VAR}={raw!r}: expected a positive number of gigabytes "
                            f"(default {DEFAULT_MEMORY_GB:g})")
    return gb * 1e9


def _lower(A):
    """cvxopt spmatrix of the lower triangle of scipy ``A`` (no Python lists: arrays through the buffer protocol)."""
    import cvxopt
    A = sp.tril(A).tocoo()
    return cvxopt.spmatrix(cvxopt.matrix(np.ascontiguousarray(A.data, dtype=np.float64)),
                           cvxopt.matrix(A.row.astype(np.int64)), cvxopt.matrix(A.col.astype(np.int64)), A.shape)


def _symmetric_graph(A) -> sp.csr_matrix:
    """Adjacency (no self loops, symmetric pattern) of sparse ``A``."""
    G = sp.csr_matrix(A, copy=True)
    G.data[:] = 1.0
    G = (G + G.T).tocsr()
    G.setdiag(0.0)
    G.eliminate_zeros()
    return G


def fill_reducing_order(A) -> np.ndarray:
    """A permutation of symmetric sparse ``A`` that keeps its Cholesky factor sparse: METIS nested dissection
    (pymetis) where installed, else approximate minimum degree (cvxopt's AMD). METIS orders the graph of the
    nodes (DOFs with the same row pattern, e.g. a node's three displacements, merged: the ordering only changes the
    fill, never the result); on 3-D solids its factor is ~0.6x AMD's (measured on the joints' bodies)."""
    n = A.shape[0]
    try:
        import pymetis
    except ImportError:
        import cvxopt.amd
        return np.asarray(cvxopt.amd.order(_lower(A))).ravel().astype(np.int64)
    G = _symmetric_graph(A)
    # supervariables: rows with the same closed pattern (hash of the columns and the row itself)
    P = (G + sp.identity(n, format="csr")).tocsr()
    P.sort_indices()
    cols = P.indices.astype(np.uint64)
    h = (cols * np.uint64(0x9E3779B97F4A7C15)) ^ (cols >> np.uint64(7))
    key = np.add.reduceat(h, P.indptr[:-1]) if P.nnz else np.zeros(n, np.uint64)
    key = key ^ np.diff(P.indptr).astype(np.uint64)
    _, group = np.unique(key, return_inverse=True)
    m = int(group.max()) + 1 if n else 0
    E = sp.csr_matrix((np.ones(n), (np.arange(n), group)), shape=(n, m))
    Q = _symmetric_graph(E.T @ G @ E) if m > 1 else sp.csr_matrix((m, m))
    if m <= 2 or Q.nnz == 0:
        return np.arange(n, dtype=np.int64)
    xadj, adjncy = Q.indptr.astype(np.int64), Q.indices.astype(np.int64)
    if hasattr(pymetis, "CSRAdjacency"):   # pymetis 2025 on; the xadj/adjncy keywords are deprecated there
        perm, _ = pymetis.nested_dissection(adjacency=pymetis.CSRAdjacency(xadj, adjncy))
    else:
        perm, _ = pymetis.nested_dissection(xadj=xadj, adjncy=adjncy)
    rank = np.empty(m, np.int64)
    rank[np.asarray(perm, dtype=np.int64)] = np.arange(m)
    return np.argsort(rank[group], kind="stable").astype(np.int64)


def _count_factor_nonzeros(indptr, indices, n):   # pragma: no cover - compiled by numba
    parent = np.full(n, -1, np.int64)
    ancestor = np.full(n, -1, np.int64)
    for i in range(n):                     # elimination tree (Liu, path compression)
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            if j >= i:
                continue
            while ancestor[j] != -1 and ancestor[j] != i:
                nxt = ancestor[j]
                ancestor[j] = i
                j = nxt
            if ancestor[j] == -1:
                ancestor[j] = i
                parent[j] = i
    mark = np.full(n, -1, np.int64)
    total = n                              # the diagonal
    for i in range(n):                     # row i of L: the row subtree of A's row i (one step per nonzero)
        mark[i] = i
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            if j >= i:
                continue
            while mark[j] != i:
                mark[j] = i
                total += 1
                j = parent[j]
    return total


@functools.lru_cache(maxsize=1)
def _compiled_count():
    try:
        from numba import njit
    except ImportError:   # numba is a dependency; plain Python is the same algorithm, only slower
        return _count_factor_nonzeros
    return njit(cache=True)(_count_factor_nonzeros)


def factor_nonzeros(A, order) -> int:
    """Nonzeros of the Cholesky factor L of P A Pᵀ (P: the permutation ``order``), diagonal included, counted
    exactly from the elimination tree without factorizing (symbolic, O(nnz(L)) steps)."""
    order = np.asarray(order, dtype=np.int64)
    B = sp.csr_matrix(_symmetric_graph(A)[order][:, order])
    B.sort_indices()
    return int(_compiled_count()(B.indptr.astype(np.int64), B.indices.astype(np.int64), B.shape[0]))


class _OrderedCholesky:
    """CHOLMOD LLᵀ of a symmetric positive definite matrix in a given order (reused for every right-hand side)."""

    def __init__(self, A, order):
        import cvxopt
        import cvxopt.cholmod as cholmod
        self.n = A.shape[0]
        Al = _lower(A)
        with _exact_order():
            self._F = cholmod.symbolic(Al, p=cvxopt.matrix(np.asarray(order, dtype=np.int64)))
            cholmod.numeric(Al, self._F)

    def solve(self, b) -> np.ndarray:
        import cvxopt
        import cvxopt.cholmod as cholmod
        b = np.asarray(b, dtype=np.float64)
        B = cvxopt.matrix(np.asfortranarray(b.reshape(self.n, -1)))
        cholmod.solve(self._F, B)
        return np.array(B).reshape(b.shape)


class _exact_order:
    """CHOLMOD options for a factorization in exactly the given order (no AMD/METIS alternatives, no postordering
    that could move the retained DOFs), restored afterwards."""

    def __enter__(self):
        import cvxopt.cholmod as cholmod
        self._saved = dict(cholmod.options)
        cholmod.options.update({"nmethods": 1, "postorder": False, "supernodal": 2})

    def __exit__(self, *exc):
        import cvxopt.cholmod as cholmod
        cholmod.options.clear()
        cholmod.options.update(self._saved)


class _CholmodFactorStruct(ctypes.Structure):
    """Head of CHOLMOD's ``cholmod_factor`` (cholmod.h, CHOLMOD 4 and 5): the supernodal factor's arrays, which
    cvxopt does not expose (its ``getfactor`` copies the whole factor and leaves it unusable for solves)."""
    _fields_ = [("n", ctypes.c_size_t), ("minor", ctypes.c_size_t), ("Perm", ctypes.c_void_p),
                ("ColCount", ctypes.c_void_p), ("IPerm", ctypes.c_void_p), ("nzmax", ctypes.c_size_t),
                ("p", ctypes.c_void_p), ("i", ctypes.c_void_p), ("x", ctypes.c_void_p), ("z", ctypes.c_void_p),
                ("nz", ctypes.c_void_p), ("next", ctypes.c_void_p), ("prev", ctypes.c_void_p),
                ("nsuper", ctypes.c_size_t), ("ssize", ctypes.c_size_t), ("xsize", ctypes.c_size_t),
                ("maxcsize", ctypes.c_size_t), ("maxesize", ctypes.c_size_t), ("super", ctypes.c_void_p),
                ("pi", ctypes.c_void_p), ("px", ctypes.c_void_p), ("s", ctypes.c_void_p),
                ("ordering", ctypes.c_int), ("is_ll", ctypes.c_int), ("is_super", ctypes.c_int),
                ("is_monotonic", ctypes.c_int), ("itype", ctypes.c_int), ("xtype", ctypes.c_int),
                ("dtype", ctypes.c_int)]


def _supernodal_trailing_block(F, n: int, ni: int):
    """L[ni:, ni:] (dense, lower) read in place from CHOLMOD's numeric supernodal LLᵀ ``F`` of order ``n``; None
    when the factor does not look like one with 64-bit indices and double values (another CHOLMOD layout): every
    field is checked before any array is read, and the diagonal read is compared with ``cholmod.diag``."""
    import cvxopt.cholmod as cholmod
    get = ctypes.pythonapi.PyCapsule_GetPointer
    get.restype, get.argtypes = ctypes.c_void_p, [ctypes.py_object, ctypes.c_char_p]
    try:
        f = _CholmodFactorStruct.from_address(get(F, b"CHOLMOD FACTOR D L"))
    except (ValueError, TypeError):
        return None
    ns = int(f.nsuper)
    if not (f.n == n and f.is_ll == 1 and f.is_super == 1 and f.itype == 2 and f.xtype == 1 and f.dtype == 0
            and 0 < ns <= n and f.xsize >= n and f.super and f.pi and f.px and f.s and f.x):
        return None

    def arr(ptr, k, ctype):
        return np.ctypeslib.as_array((ctype * k).from_address(ptr))

    sup, pi, px = arr(f.super, ns + 1, ctypes.c_int64), arr(f.pi, ns + 1, ctypes.c_int64), arr(f.px, ns + 1, ctypes.c_int64)
    if sup[0] != 0 or sup[ns] != n or pi[ns] != f.ssize or px[ns] > f.xsize:
        return None
    rows_all, x = arr(f.s, int(f.ssize), ctypes.c_int64), arr(f.x, int(f.xsize), ctypes.c_double)
    nr = n - ni
    Lrr = np.zeros((nr, nr))
    for k in range(int(np.searchsorted(sup, ni, side="right")) - 1, ns):
        k1, k2 = int(sup[k]), int(sup[k + 1])
        if k2 <= ni:
            continue
        rows = rows_all[pi[k]:pi[k + 1]]
        block = x[px[k]:px[k] + rows.size * (k2 - k1)].reshape(k2 - k1, rows.size).T   # column-major, rows.size rows
        c0 = max(k1, ni)
        keep = rows >= ni
        Lrr[np.ix_(rows[keep] - ni, np.arange(c0, k2) - ni)] = block[np.ix_(keep, np.arange(c0 - k1, k2 - k1))]
    Lrr = np.tril(Lrr)
    if not np.allclose(np.diag(Lrr), np.asarray(cholmod.diag(F)).ravel()[ni:], rtol=0.0, atol=0.0):
        return None
    return Lrr


class _FactorInterior:
    """K_ii⁻¹ from the partial factorization of a body (interior first, retained last): with P A_δ Pᵀ = L Lᵀ,
    solving L y = P [b; 0], zeroing y's retained part and solving Lᵀ z = y gives z = P [K_ii⁻¹ b; 0] (L_ii, L_ri do
    not depend on the δ added to the retained diagonal): one factorization serves S and the extension."""

    def __init__(self, F, n: int, ni: int):
        self._F, self.n, self.ni = F, n, ni

    def solve(self, b) -> np.ndarray:
        import cvxopt
        import cvxopt.cholmod as cholmod
        b = np.asarray(b, dtype=np.float64)
        cols = b.reshape(self.ni, -1)
        B = cvxopt.matrix(np.asfortranarray(np.vstack([cols, np.zeros((self.n - self.ni, cols.shape[1]))])))
        cholmod.solve(self._F, B, sys=7)    # P b
        cholmod.solve(self._F, B, sys=4)    # L⁻¹
        Y = np.array(B)
        Y[self.ni:] = 0.0   # positions ni.. of the permuted order are the retained DOFs
        B = cvxopt.matrix(np.asfortranarray(Y))
        cholmod.solve(self._F, B, sys=5)    # L⁻ᵀ
        cholmod.solve(self._F, B, sys=8)    # Pᵀ
        return np.array(B)[: self.ni].reshape(b.shape)


@functools.lru_cache(maxsize=1)
def reads_factor_in_place() -> bool:
    """True when CHOLMOD's supernodal factor can be read in place (:func:`_supernodal_trailing_block` on a small
    probe agrees with cvxopt's own copy of the factor)."""
    try:
        import cvxopt
        import cvxopt.cholmod as cholmod
    except ImportError:
        return False
    m = 40
    A = sp.diags([-1.0, 4.0, -1.0], [-1, 0, 1], shape=(m, m), format="csr") + sp.csr_matrix(np.ones((m, m)) * 0.01)
    with _exact_order():
        F = cholmod.symbolic(_lower(A), p=cvxopt.matrix(np.arange(m, dtype=np.int64)))
        cholmod.numeric(_lower(A), F)
    Lrr = _supernodal_trailing_block(F, m, m // 2)
    if Lrr is None:
        return False
    L = cholmod.getfactor(F)
    ref = np.zeros((m, m))
    ref[np.asarray(L.I).ravel(), np.asarray(L.J).ravel()] = np.asarray(L.V).ravel()
    return bool(np.allclose(Lrr, ref[m // 2:, m // 2:], rtol=1e-14, atol=0.0))


def _partial_factor_schur(A, ni: int, order_i):
    """S of one body, ``A`` = [[K_ii, K_ir], [K_ri, K_rr]] with its ``ni`` interior rows first: CHOLMOD LLᵀ of
    A + δ E_r in the order (interior in ``order_i``, retained last), S = L_rr L_rrᵀ − δ I (module doc). Returns
    (S, interior solver from the same factor, or None where the factor could only be copied out).
    Raises ArithmeticError when K_ii is not positive definite, ValueError when CHOLMOD moved the retained rows."""
    import cvxopt
    import cvxopt.cholmod as cholmod

    n = A.shape[0]
    nr = n - ni
    d = A.diagonal()[ni:]
    delta = float(np.mean(np.abs(d))) if nr else 1.0
    delta = delta if delta > 0 else 1.0
    p = np.concatenate([np.asarray(order_i, dtype=np.int64), np.arange(ni, n, dtype=np.int64)])
    Ad = _lower(A + sp.diags(np.r_[np.zeros(ni), np.full(nr, delta)]))
    with _exact_order():
        F = cholmod.symbolic(Ad, p=cvxopt.matrix(p))
        cholmod.numeric(Ad, F)
    del Ad
    # CHOLMOD must have kept the order given (the retained block last): checked on the permutation itself
    x = cvxopt.matrix(np.arange(n, dtype=np.float64))
    cholmod.solve(F, x, sys=7)
    if not np.array_equal(np.asarray(x).ravel().astype(np.int64), p):
        raise ValueError("CHOLMOD did not keep the retained DOFs last")
    Lrr = _supernodal_trailing_block(F, n, ni) if reads_factor_in_place() else None
    interior = _FactorInterior(F, n, ni) if Lrr is not None else None
    if Lrr is None:   # the trailing block from cvxopt's copy of the whole factor (which leaves F symbolic)
        Lf = cholmod.getfactor(F)
        del F
        Lrr_s = Lf[ni:, ni:]
        del Lf
        Lrr = np.zeros((nr, nr))
        Lrr[np.asarray(Lrr_s.I).ravel(), np.asarray(Lrr_s.J).ravel()] = np.asarray(Lrr_s.V).ravel()
        del Lrr_s
    S = Lrr @ Lrr.T
    S[np.diag_indices(nr)] -= delta
    return 0.5 * (S + S.T), interior


def _block_columns(ni: int, factor_bytes: float, budget: float) -> int:
    """Retained columns back-substituted at once: three dense n_i-row blocks (right-hand side, solution, the
    solver's copy) in what the budget leaves beside the factor; at least :data:`MIN_BLOCK`."""
    free = budget - factor_bytes
    return int(max(MIN_BLOCK, min(MAX_BLOCK, free // (3 * 8 * max(ni, 1)))))


def _nonmkl_schur(K, r, mode: str):
    """S, extension and the number of factorizations without MKL, body by body (module doc). ``mode`` "cholmod":
    each body's partial factorization where its factor fits :func:`memory_budget`, else its back-substitution in
    budget-sized column blocks; "blockwise": the back-substitution for every body. Returns also the count of bodies
    condensed by partial factorization."""
    from scipy.sparse.csgraph import connected_components

    from femcheck.fe.linear_solver import cvxopt_available, factorize

    budget = memory_budget()
    n = K.shape[0]
    mask = np.zeros(n, bool)
    mask[r] = True
    i = np.flatnonzero(~mask)
    Kii = sp.csr_matrix(K[i][:, i])
    Kir = sp.csr_matrix(K[i][:, r])
    Krr = sp.csr_matrix(K[r][:, r])
    S = Krr.toarray()
    ncomp, label = connected_components(Kii, directed=False)
    facs, nfac, npartial = [], 0, 0
    cholmod_ok = cvxopt_available()
    for c in range(ncomp):
        ic = np.flatnonzero(label == c)
        Kc = sp.csc_matrix(Kir[ic])
        cols = np.flatnonzero(np.diff(Kc.indptr))
        if not cols.size:   # a body the retained set does not touch: its interior stays at rest
            continue
        Kbb = sp.csr_matrix(Kii[ic][:, ic])
        Kbr = sp.csc_matrix(Kc[:, cols])
        ni = ic.size
        if cholmod_ok:
            order = fill_reducing_order(Kbb)
            if mode == "cholmod":
                A = sp.bmat([[Kbb, Kbr], [Kbr.T, Krr[cols][:, cols]]], format="csr")
                per_nonzero = BYTES_PER_FACTOR_NONZERO if reads_factor_in_place() else BYTES_PER_COPIED_NONZERO
                need = factor_nonzeros(A, np.r_[order, np.arange(ni, ni + cols.size)]) * per_nonzero
                if need <= budget:
                    try:
                        Sb, interior = _partial_factor_schur(A, ni, order)
                    except (ArithmeticError, ValueError, MemoryError) as exc:
                        log.info("CHOLMOD partial factorization failed (%s); blockwise back-substitution", exc)
                    else:
                        S[np.ix_(cols, cols)] += Sb - Krr[cols][:, cols].toarray()
                        npartial += 1
                        nfac += 1
                        if interior is None:   # the factor was copied out: K_ii again for the extension
                            interior = _OrderedCholesky(Kbb, order)
                            nfac += 1
                        facs.append((ic, interior))
                        continue
                else:
                    log.info("body of %d unknowns: partial factor needs %.2f GB > %s = %.2f GB; blockwise",
                             ni, need / 1e9, MEMORY_VAR, budget / 1e9)
                del A
            fac = _OrderedCholesky(Kbb, order)
            fac_bytes = factor_nonzeros(Kbb, order) * 8.0
        else:
            fac = factorize(sp.csc_matrix(Kbb), "auto")
            fac_bytes = 0.0   # unknown for a solver of another library: the blocks alone are sized
        nfac += 1
        facs.append((ic, fac))
        Krc = sp.csr_matrix(Kbr.T)
        step = _block_columns(ni, fac_bytes, budget)
        for j in range(0, cols.size, step):
            X = fac.solve(Kbr[:, j:j + step].toarray())
            S[np.ix_(cols, cols[j:j + step])] -= Krc @ X
            del X

    def extend(u_r):
        y = Kir @ u_r
        q = np.zeros(n)
        qi = np.zeros(i.size)
        for ic, fac in facs:
            qi[ic] = -fac.solve(y[ic])
        q[i] = qi
        return q

    return 0.5 * (S + S.T), extend, nfac, npartial, len(facs)
