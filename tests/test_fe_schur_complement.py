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
    # the default without MKL: CHOLMOD's partial factorization, body by body
    assert condense(K, r).method == ("cholmod" if cvxopt_available() else "blockwise")
    # a budget too small for a body's partial factor sends that body to the back-substitution
    monkeypatch.setenv("FEMCHECK_SCHUR_MEMORY_GB", "1e-7")   # 100 B
    assert condense(K, r).method == "blockwise"


needs_cvxopt = pytest.mark.skipif(not cvxopt_available(), reason="cvxopt (CHOLMOD) not installed")


def _dense_schur(K, r):
    i = np.setdiff1d(np.arange(K.shape[0]), r)
    D = K.toarray()
    return D[np.ix_(r, r)] - D[np.ix_(r, i)] @ np.linalg.solve(D[np.ix_(i, i)], D[np.ix_(i, r)])


@needs_cvxopt
def test_the_memory_budget_sizes_the_blocks_of_the_back_substitution(monkeypatch):
    from femcheck.fe import schur_complement as sc

    K, r = _two_floating_bodies()
    S_ref = _dense_schur(K, r)
    ni = K.shape[0] // 2 - r.size // 2          # interior unknowns of one body
    widths = []
    solve = sc._OrderedCholesky.solve
    monkeypatch.setattr(sc._OrderedCholesky, "solve", lambda self, b: (widths.append(np.shape(b)[1:] or (1,)), solve(self, b))[1])
    budget_gb = 4e-3
    monkeypatch.setenv("FEMCHECK_SCHUR_MEMORY_GB", str(budget_gb))
    monkeypatch.setenv("FEMCHECK_SCHUR_METHOD", "blockwise")
    monkeypatch.setattr("femcheck.fe.linear_solver.pardiso_available", lambda: False)
    c = sc.condense(K, r)
    assert c.method == "blockwise"
    # three dense n_i-row blocks (right-hand side, solution, the solver's copy) beside the factor fit the budget
    fac_bytes = 8.0 * sc.factor_nonzeros(K[:ni][:, :ni], sc.fill_reducing_order(K[:ni][:, :ni]))
    limit = (budget_gb * 1e9 - fac_bytes) // (3 * 8 * ni)
    assert sc.MIN_BLOCK < limit < r.size // 2     # this budget splits each body's 144 columns into blocks
    assert max(w[0] for w in widths) <= limit
    assert len(widths) >= 2 * np.ceil(r.size // 2 / limit)   # every column of both bodies back-substituted
    # round-off of direct factorizations of a well-conditioned K_ii (condition ≈ 1e3)
    assert np.abs(c.S - S_ref).max() <= 1e-10 * np.abs(S_ref).max()
    # a budget that holds the partial factor: one factorization per body, no back-substitution at all
    monkeypatch.setenv("FEMCHECK_SCHUR_METHOD", "auto")
    monkeypatch.setenv("FEMCHECK_SCHUR_MEMORY_GB", "1")
    widths.clear()
    c = sc.condense(K, r)
    assert c.method == "cholmod" and c.factorizations == 2 and not widths
    assert np.abs(c.S - S_ref).max() <= 1e-10 * np.abs(S_ref).max()


@needs_cvxopt
def test_the_copied_factor_path_gives_the_same_condensation(monkeypatch):
    """Where CHOLMOD's factor cannot be read in place (another CHOLMOD layout), the trailing block comes from
    cvxopt's copy of the factor and K_ii is factorized again for the extension: same S and extension."""
    from femcheck.fe import schur_complement as sc

    K, r = _two_floating_bodies()
    monkeypatch.setattr(sc, "reads_factor_in_place", lambda: False)
    c = sc.condense(K, r, method="cholmod")
    S_ref = _dense_schur(K, r)
    assert c.method == "cholmod" and c.factorizations == 4   # per body: the partial factor, then K_ii
    assert np.abs(c.S - S_ref).max() <= 1e-10 * np.abs(S_ref).max()   # round-off (condition ≈ 1e3)
    u_r = np.random.default_rng(5).standard_normal(r.size)
    assert np.abs(K[r] @ c.extend(u_r) - S_ref @ u_r).max() <= 1e-10 * np.abs(S_ref @ u_r).max()


@pytest.mark.parametrize("metis", [False, True])
def test_factor_nonzeros_is_the_fill_of_the_dense_cholesky(monkeypatch, metis):
    import sys

    from femcheck.fe import schur_complement as sc

    if metis:
        pytest.importorskip("pymetis")
    elif cvxopt_available():
        monkeypatch.setitem(sys.modules, "pymetis", None)    # the AMD fallback (no METIS wheel for the platform)
    else:
        pytest.skip("cvxopt (AMD) not installed")
    m = 6
    K, _ = _two_floating_bodies(m)
    A = sp.csr_matrix(K[: m ** 3][:, : m ** 3])
    rng = np.random.default_rng(1)
    A = sp.triu(A, 1)
    A.data = -rng.uniform(0.5, 1.5, A.nnz)                  # random weights: no numerical cancellation of fill
    A = (A + A.T).tocsr()
    A = A + sp.diags(np.asarray(abs(A).sum(axis=1)).ravel() + 1.0)   # diagonally dominant: positive definite
    order = sc.fill_reducing_order(A)
    assert np.array_equal(np.sort(order), np.arange(A.shape[0]))     # a permutation
    L = np.linalg.cholesky(A.toarray()[np.ix_(order, order)])
    # structural count, exact: every position the elimination fills is nonzero for generic weights
    assert sc.factor_nonzeros(A, order) == int(np.count_nonzero(np.abs(L) > 1e-300))
    # the fill-reducing order beats the natural one on this 3-D grid
    assert sc.factor_nonzeros(A, order) < sc.factor_nonzeros(A, np.arange(A.shape[0]))


@pytest.mark.parametrize("raw", ["abc", "-1", "0", "nan", "inf"])
def test_a_bad_memory_budget_is_one_line_naming_the_variable(monkeypatch, raw):
    from femcheck.errors import FemcheckError
    from femcheck.fe import linear_solver
    from femcheck.fe.schur_complement import condense

    K, r = _two_floating_bodies(4)
    monkeypatch.setenv("FEMCHECK_SCHUR_MEMORY_GB", raw)
    monkeypatch.setattr(linear_solver, "pardiso_available", lambda: False)
    with pytest.raises(FemcheckError) as exc:
        condense(K, r)
    msg = str(exc.value)
    assert msg.startswith(f"FEMCHECK_SCHUR_MEMORY_GB={raw!r}: expected a positive number") and "\n" not in msg
