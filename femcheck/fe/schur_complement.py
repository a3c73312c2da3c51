"""Dense Schur complement of a sparse symmetric matrix onto a small index set.

    S = K_rr − K_ri K_ii⁻¹ K_ir        (K: n x n sparse symmetric, r: the n_r retained indices)

:func:`schur_complement` asks MKL PARDISO for it during the factorization (``iparm[35] = 1``, the
retained rows marked in ``perm``): the elimination of the interior stops at the retained block, whose
dense update *is* S, so no right-hand sides are back-substituted at all. Where pypardiso/MKL is not
available, or PARDISO returns an error, the blockwise fallback factorizes K_ii and back-substitutes the
retained columns (``BLOCK`` at a time). K_ii must be nonsingular; K_rr (and S) may be singular (floating
bodies held only by their retained contact DOFs).

:func:`condense` returns S together with the interior extension q_i = −K_ii⁻¹ K_ir u_r of a retained
displacement (the recovery after a condensed contact solve) from the *same* factorization: PARDISO keeps
its partial factorization LDLᵀ of K_ii and back-substitutes [0; u_r] (phase 333: the backward step with the
retained part fixed at u_r gives x_i = −L_iiᵀ⁻¹ L_riᵀ u_r = −K_ii⁻¹ K_ir u_r); the blockwise path keeps its
per-body factorizations. No second factorization of the interior is made.

Without MKL, :func:`_cholmod_schur` gets S from CHOLMOD's supernodal Cholesky (cvxopt) in the same way
as PARDISO does: the interior is ordered first (AMD on K_ii) and the retained DOFs last, so the trailing
block of the factor is the Cholesky factor of the Schur complement (George & Liu 1981, §2.3):

    P K_δ Pᵀ = L Lᵀ,  L = [[L_ii, 0], [L_ri, L_rr]]  ⇒  K_δ,rr − K_ri K_ii⁻¹ K_ir = L_rr L_rrᵀ,

where K_δ = K + δ E_r adds δ to the retained diagonal only. S itself may be singular (floating bodies),
S + δ I is positive definite for any δ > 0, and S = L_rr L_rrᵀ − δ I exactly (S is linear in K_rr);
δ is the mean retained diagonal, so the subtraction loses no more than round-off of S's own scale. The
interior extension factorizes K_ii once per body after that factor is released (cvxopt exposes the factor
only as a copy that leaves it unusable for solves, and the bodies' own fill-reducing orderings keep the
memory below that of the constrained ordering). Without MKL, systems up to ``CHOLMOD_SCHUR_MAX_DOFS`` unknowns take
the CHOLMOD path and larger ones the blockwise back-substitution (one forward and backward solve per retained column,
bounded memory); ``FEMCHECK_SCHUR_METHOD=cholmod`` or ``blockwise`` forces one. Measured on the universal joint's default level (371,298 DOFs, 5,730 retained,
``check_joint(case, "universal", "default")`` with ``FEMCHECK_LINEAR_SOLVER=cholmod``, load average ≈ 1–2):
CHOLMOD path 146.9 s wall, peak RSS 14.9 GB (the AMD-ordered factor and the copy cvxopt's ``getfactor``
makes of it); blockwise > 900 s (killed) at ≈ 6 GB; PARDISO 49–67 s at ≈ 5.2 GB.
"""
from __future__ import annotations

import ctypes
import logging
import time

import numpy as np
import scipy.sparse as sp

log = logging.getLogger(__name__)

#: columns per block of the fallback back-substitution (bounds memory to n_i x BLOCK x 8 B)
BLOCK = 256
#: without MKL, systems up to this many unknowns take CHOLMOD's partial factorization, larger ones the blockwise
#: back-substitution (measured, no MKL, load average 8: the universal joint's coarse level, 234,510 unknowns and
#: 2,970 retained, CHOLMOD 96 s and 7.7 GB peak, blockwise not done after 15 min at 3.5 GB; its default level,
#: 371,298 unknowns, CHOLMOD 14.9 GB: module doc)
CHOLMOD_SCHUR_MAX_DOFS = 300_000


def schur_complement(K, r: np.ndarray, *, method: str = "auto") -> np.ndarray:
    """(n_r, n_r) dense S of symmetric sparse ``K`` onto the sorted indices ``r`` (module doc).

    method: "auto" (PARDISO, else the fallback), "pardiso", "blockwise"."""
    c = condense(K, r, method=method)
    S = c.S
    c.free()
    return S


class SchurCondensation:
    """S = K_rr − K_ri K_ii⁻¹ K_ir (``S``, (n_r, n_r) dense) and the interior extension of a retained
    displacement from the same factorization (:meth:`extend`). ``method`` "pardiso" | "blockwise";
    ``factorizations`` made (PARDISO: 1, blockwise: one per body touching r); ``seconds`` wall time of S."""

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
        from femcheck.fe.linear_solver import cvxopt_available, pardiso_available, preferred
        if preferred() not in ("auto", "pardiso") or not pardiso_available():
            # the user's non-MKL choice, or no MKL: the blockwise fallback (bounded memory), or CHOLMOD's
            # constrained-order factorization where FEMCHECK_SCHUR_METHOD=cholmod asks for it (much faster,
            # but its AMD fill took 14.9 GB on the universal default joint: module doc)
            import os
            choice = os.environ.get("FEMCHECK_SCHUR_METHOD", "auto").strip().lower()
            if choice not in ("auto", "blockwise", "cholmod"):
                from femcheck.errors import FemcheckError
                raise FemcheckError(f"FEMCHECK_SCHUR_METHOD={choice!r}: expected auto, blockwise or cholmod")
            if choice == "auto":   # CHOLMOD's partial factorization where its fill fits in memory (module doc)
                choice = "cholmod" if K.shape[0] <= CHOLMOD_SCHUR_MAX_DOFS else "blockwise"
            method = "cholmod" if choice == "cholmod" and cvxopt_available() else "blockwise"
    if method == "cholmod":
        try:
            S, ext, nfac = _cholmod_schur(K, r)
            dt = time.perf_counter() - t0
            log.info("Schur complement %d -> %d with CHOLMOD (retained last) in %.2f s", K.shape[0], r.size, dt)
            return SchurCondensation(K, r, S, "cholmod", 1 + nfac, dt, ext)
        except (ImportError, ArithmeticError, ValueError, MemoryError) as exc:
            log.info("CHOLMOD Schur complement failed (%s); blockwise back-substitution", exc)
    if method in ("auto", "pardiso"):
        try:
            S, ext, fre = _pardiso_schur(K, r)
            dt = time.perf_counter() - t0
            log.info("Schur complement %d -> %d with PARDISO in %.2f s", K.shape[0], r.size, dt)
            return SchurCondensation(K, r, S, "pardiso", 1, dt, ext, fre)
        except (ImportError, OSError, RuntimeError) as exc:
            if method == "pardiso":
                raise
            log.info("PARDISO Schur complement unavailable (%s); blockwise back-substitution", exc)
    S, ext, nfac = _blockwise_schur(K, r)
    dt = time.perf_counter() - t0
    log.info("Schur complement %d -> %d blockwise in %.2f s (%d factorizations)", K.shape[0], r.size, dt, nfac)
    return SchurCondensation(K, r, S, "blockwise", nfac, dt, ext)


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


def _cholmod_schur(K, r):
    """S, extension and release from one CHOLMOD factorization with the retained DOFs ordered last
    (module doc). Raises ArithmeticError when K_ii is not positive definite."""
    import cvxopt
    import cvxopt.amd
    import cvxopt.cholmod as cholmod

    n, nr = K.shape[0], r.size
    mask = np.zeros(n, bool)
    mask[r] = True
    i = np.flatnonzero(~mask)
    ni = i.size
    d = K.diagonal()[r]
    delta = float(np.mean(np.abs(d))) if nr else 1.0
    delta = delta if delta > 0 else 1.0

    def lower(A):
        A = sp.tril(A).tocoo()
        return cvxopt.spmatrix(A.data, A.row.astype(np.int64).tolist(), A.col.astype(np.int64).tolist(), A.shape)

    order_i = np.asarray(cvxopt.amd.order(lower(sp.csr_matrix(K[i][:, i])))).ravel()
    p = np.concatenate([i[order_i], r])
    Kd = lower(K + sp.diags(np.where(mask, delta, 0.0)))
    saved = dict(cholmod.options)
    try:
        # exactly the given order (no AMD/METIS alternatives, no postordering that could move r)
        cholmod.options.update({"nmethods": 1, "postorder": False, "supernodal": 2})
        F = cholmod.symbolic(Kd, p=cvxopt.matrix(p.tolist(), tc="i"))
        cholmod.numeric(Kd, F)
    finally:
        cholmod.options.clear()
        cholmod.options.update(saved)
    # CHOLMOD must have kept the order given (the retained block last): checked on the permutation itself
    x = cvxopt.matrix(np.arange(n, dtype=np.float64))
    cholmod.solve(F, x, sys=7)
    if not np.array_equal(np.asarray(x).ravel().astype(np.int64), p):
        raise ValueError("CHOLMOD did not keep the retained DOFs last")
    # the trailing block of the factor only (cvxopt's getfactor copies L and leaves F symbolic)
    Lf = cholmod.getfactor(F)
    del F
    Lrr_s = Lf[ni:, ni:]
    del Lf
    Lrr = np.zeros((nr, nr))
    Lrr[np.asarray(Lrr_s.I).ravel(), np.asarray(Lrr_s.J).ravel()] = np.asarray(Lrr_s.V).ravel()
    del Lrr_s
    S = Lrr @ Lrr.T
    S[np.diag_indices(nr)] -= delta
    del Lrr
    # the extension: K_ii per body, factorized after the big factor is gone (memory), default ordering
    extend, facs, _ = _interior_extension(K, r)
    return 0.5 * (S + S.T), extend, len(facs)


def _interior_extension(K, r):
    """q = [−K_ii⁻¹ K_ir u_r; 0] as a function of u_r, from one factorization per body of K_ii (K_ii is
    block diagonal per body: the bodies meet only at retained DOFs). Returns (extend, bodies, K_ir) with
    bodies = [(interior indices of the body, its factorization)] for reuse (:func:`_blockwise_schur`)."""
    from scipy.sparse.csgraph import connected_components

    from femcheck.fe.linear_solver import factorize

    n = K.shape[0]
    mask = np.zeros(n, bool)
    mask[r] = True
    i = np.flatnonzero(~mask)
    Kii = sp.csr_matrix(K[i][:, i])
    Kir = sp.csr_matrix(K[i][:, r])
    ncomp, label = connected_components(Kii, directed=False)
    facs = []
    for c in range(ncomp):
        ic = np.flatnonzero(label == c)
        if not sp.csr_matrix(Kir[ic]).nnz:  # a body the retained set does not touch: its interior stays at rest
            continue
        facs.append((ic, factorize(sp.csc_matrix(Kii[ic][:, ic]), "auto")))

    def extend(u_r):
        y = Kir @ u_r
        q = np.zeros(n)
        qi = np.zeros(i.size)
        for ic, fac in facs:
            qi[ic] = -fac.solve(y[ic])
        q[i] = qi
        return q

    return extend, facs, Kir


def _blockwise_schur(K, r):
    extend, facs, Kir = _interior_extension(K, r)
    S = K[r][:, r].toarray()
    # each body's factorization back-substitutes only the retained columns touching it
    for ic, fac in facs:
        Kir_c = sp.csc_matrix(Kir[ic])
        cols = np.flatnonzero(np.diff(Kir_c.indptr))
        Kc = sp.csc_matrix(Kir_c[:, cols])
        Krc = sp.csr_matrix(Kc.T)
        for j in range(0, cols.size, BLOCK):
            X = fac.solve(Kc[:, j:j + BLOCK].toarray())
            S[np.ix_(cols, cols[j:j + BLOCK])] -= Krc @ X
    return 0.5 * (S + S.T), extend, len(facs)
