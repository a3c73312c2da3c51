"""Dense Schur complement onto a retained set (femcheck.fe.schur_complement): PARDISO's own and the
CHOLMOD partial factorization (the non-MKL path) and the blockwise fallback agree with the dense formula,
also when the retained block is singular."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from femcheck.fe.linear_solver import cvxopt_available, pardiso_available
from femcheck.fe.schur_complement import schur_complement


def _two_floating_bodies(m=12):
    """Two 3-D grid Laplacians (two 'bodies', block diagonal) with their last rows retained: K_ii is
    nonsingular, while K (each body floats: zero row sums) and S are singular."""
    L = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(m, m)).tolil()
    L[0, 0] = L[m - 1, m - 1] = 1.0  # free ends: a floating body
    I = sp.identity(m)
    A = sp.kron(sp.kron(L, I), I) + sp.kron(sp.kron(I, L), I) + sp.kron(sp.kron(I, I), L)
    K = sp.block_diag([A, 2.0 * A], format="csr")
    n = K.shape[0] // 2
    r = np.r_[np.arange(n - m * m, n), np.arange(2 * n - m * m, 2 * n)]  # one face of each body
    return K, r


#: every Schur-complement path, each skipped where its solver is not installed
METHODS = ["blockwise",
           pytest.param("pardiso", marks=pytest.mark.skipif(not pardiso_available(), reason="pypardiso/MKL not installed")),
           pytest.param("cholmod", marks=pytest.mark.skipif(not cvxopt_available(), reason="cvxopt (CHOLMOD) not installed"))]


@pytest.mark.parametrize("method", METHODS)
def test_schur_complement_matches_the_dense_formula(method):
    K, r = _two_floating_bodies()
    i = np.setdiff1d(np.arange(K.shape[0]), r)
    D = K.toarray()
    S_ref = D[np.ix_(r, r)] - D[np.ix_(r, i)] @ np.linalg.solve(D[np.ix_(i, i)], D[np.ix_(i, r)])
    S = schur_complement(K, r, method=method)
    # round-off of two direct factorizations of a well-conditioned K_ii (condition ≈ 1e3)
    assert np.abs(S - S_ref).max() <= 1e-10 * np.abs(S_ref).max()
    # each floating body's rigid mode (constant) survives condensation: S annihilates it
    assert np.abs(S[:, : r.size // 2].sum(axis=1)).max() <= 1e-10 * np.abs(S_ref).max()


@pytest.mark.parametrize("method", METHODS)
def test_condensation_extends_the_retained_displacement_from_the_same_factorization(method):
    from femcheck.fe.schur_complement import condense

    K, r = _two_floating_bodies()
    i = np.setdiff1d(np.arange(K.shape[0]), r)
    D = K.toarray()
    u_r = np.random.default_rng(3).standard_normal(r.size)
    q_ref = -np.linalg.solve(D[np.ix_(i, i)], D[np.ix_(i, r)] @ u_r)
    c = condense(K, r, method=method)
    q = c.extend(u_r)
    # interior equilibrium K_ii q_i + K_ir u_r = 0 to the round-off of the direct factorization
    assert np.abs(q[i] - q_ref).max() <= 1e-10 * np.abs(q_ref).max()
    assert np.array_equal(q[r], u_r)  # the retained part is the given displacement
    # the reaction on the retained DOFs is S u_r (the definition of the Schur complement)
    assert np.abs(K[r] @ q - c.S @ u_r).max() <= 1e-10 * np.abs(c.S @ u_r).max()
    # PARDISO: one partial factorization serves S and the extension; blockwise: one per body for both;
    # CHOLMOD: per body, one constrained-order factorization serves S and the extension
    assert c.factorizations == {"pardiso": 1, "blockwise": 2, "cholmod": 2}[method]
    c.free()
    with pytest.raises(RuntimeError):
        c.extend(u_r)


def test_a_bad_non_mkl_schur_method_is_named(monkeypatch):
    from femcheck.errors import FemcheckError
    from femcheck.fe import linear_solver
    from femcheck.fe.schur_complement import condense

    K, r = _two_floating_bodies(4)
    monkeypatch.setenv("FEMCHECK_SCHUR_METHOD", "lu")
    monkeypatch.setattr(linear_solver, "pardiso_available", lambda: False)
    with pytest.raises(FemcheckError, match="FEMCHECK_SCHUR_METHOD='lu'"):
        condense(K, r)
    # the named choice is taken: CHOLMOD's constrained-order factorization where cvxopt imports
    monkeypatch.setenv("FEMCHECK_SCHUR_METHOD", "cholmod")
    assert condense(K, r).method == ("cholmod" if cvxopt_available() else "blockwise")
    monkeypatch.delenv("FEMCHECK_SCHUR_METHOD")
    # the default without MKL: CHOLMOD where the system is small enough for its fill, blockwise (bounded memory) above
    assert condense(K, r).method == ("cholmod" if cvxopt_available() else "blockwise")
    from femcheck.fe import schur_complement
    monkeypatch.setattr(schur_complement, "CHOLMOD_SCHUR_MAX_DOFS", K.shape[0] - 1)
    assert condense(K, r).method == "blockwise"
