"""Dense Schur complement of a sparse symmetric matrix onto a small index set.

    S = K_rr − K_ri K_ii⁻¹ K_ir        (K: n x n sparse symmetric, r: the n_r retained indices)

:func:`schur_complement` asks MKL PARDISO for it during the factorization (``iparm[35] = 1``, the
retained rows marked in ``perm``): the elimination of the interior stops at the retained block, whose
dense update *is* S, so no right-hand sides are back-substituted at all. Where pypardiso/MKL is not
available, or PARDISO returns an error, the blockwise fallback factorizes K_ii and back-substitutes the
retained columns (``BLOCK`` at a time). K_ii must be nonsingular; K_rr (and S) may be singular (floating
bodies held only by their retained contact DOFs).
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


def schur_complement(K, r: np.ndarray, *, method: str = "auto") -> np.ndarray:
    """(n_r, n_r) dense S of symmetric sparse ``K`` onto the sorted indices ``r`` (module doc).

    method: "auto" (PARDISO, else the fallback), "pardiso", "blockwise"."""
    K = sp.csr_matrix(K, dtype=np.float64)
    r = np.asarray(r, dtype=np.int64)
    t0 = time.perf_counter()
    if method in ("auto", "pardiso"):
        try:
            S = _pardiso_schur(K, r)
            log.info("Schur complement %d -> %d with PARDISO in %.2f s", K.shape[0], r.size, time.perf_counter() - t0)
            return S
        except (ImportError, OSError, RuntimeError) as exc:
            if method == "pardiso":
                raise
            log.info("PARDISO Schur complement unavailable (%s); blockwise back-substitution", exc)
    S = _blockwise_schur(K, r)
    log.info("Schur complement %d -> %d blockwise in %.2f s", K.shape[0], r.size, time.perf_counter() - t0)
    return S


def _pardiso_schur(K, r) -> np.ndarray:
    import pypardiso

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

    def call(phase):
        solver._mkl_pardiso(solver.pt.ctypes.data_as(ctypes.POINTER(solver._pt_type[0])),
                            ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(1)),
                            ctypes.byref(ctypes.c_int32(-2)), ctypes.byref(ctypes.c_int32(phase)),
                            ctypes.byref(ctypes.c_int32(n)), A.data.ctypes.data_as(D), ia.ctypes.data_as(P),
                            ja.ctypes.data_as(P), perm.ctypes.data_as(P), ctypes.byref(ctypes.c_int32(1)),
                            iparm.ctypes.data_as(P), ctypes.byref(ctypes.c_int32(0)), b.ctypes.data_as(D),
                            x.ctypes.data_as(D), ctypes.byref(err))

    call(12)
    code = err.value
    call(-1)  # release PARDISO's memory
    if code != 0:
        raise RuntimeError(f"PARDISO Schur complement: error {code}")
    S = x.reshape(ns, ns)
    return 0.5 * (S + S.T)


def _blockwise_schur(K, r) -> np.ndarray:
    from scipy.sparse.csgraph import connected_components

    from femcheck.fe.linear_solver import factorize

    n = K.shape[0]
    mask = np.zeros(n, bool)
    mask[r] = True
    i = np.flatnonzero(~mask)
    Kii = sp.csr_matrix(K[i][:, i])
    Kir = sp.csr_matrix(K[i][:, r])
    S = K[r][:, r].toarray()
    # K_ii block diagonal per body: factorize each block, back-substitute only the columns touching it
    ncomp, label = connected_components(Kii, directed=False)
    for c in range(ncomp):
        ic = np.flatnonzero(label == c)
        Kir_c = sp.csc_matrix(Kir[ic])
        cols = np.flatnonzero(np.diff(Kir_c.indptr))
        if cols.size == 0:
            continue
        fac = factorize(sp.csc_matrix(Kii[ic][:, ic]), "auto")
        Kc = sp.csc_matrix(Kir_c[:, cols])
        Krc = sp.csr_matrix(Kc.T)
        for j in range(0, cols.size, BLOCK):
            X = fac.solve(Kc[:, j:j + BLOCK].toarray())
            S[np.ix_(cols, cols[j:j + BLOCK])] -= Krc @ X
    return 0.5 * (S + S.T)
