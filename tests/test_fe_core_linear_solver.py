"""Linear solver paths agree on an elasticity system; factorizations are independent; choice is reported."""
import numpy as np
import pytest
import scipy.sparse as sp

from conftest import clamped_steel_bar
from femcheck.fe.elasticity import rigid_body_modes
from femcheck.fe.linear_solver import choose_method, cvxopt_available, factorize, pardiso_available, solve


@pytest.fixture(scope="module")
def system():
    basis, K, c = clamped_steel_bar(9, 3, 2)
    rng = np.random.default_rng(0)
    f = rng.standard_normal(basis.N)
    return c.reduce_matrix(K), c.reduce_vector(f), rigid_body_modes(basis)[c.free]


METHODS = (["superlu", "amg-cg"] + (["pardiso"] if pardiso_available() else [])
           + (["cholmod", "umfpack"] if cvxopt_available() else []))


@pytest.mark.parametrize("method", METHODS)
def test_methods_agree_with_residual(system, method):
    A, b, B = system
    kw = {"near_nullspace": B} if method == "amg-cg" else {}
    res = solve(A, b, method, **kw)
    assert res.method == method
    # direct: round-off of a system with condition ~1e8; CG stops at rtol 1e-10 of ||b||
    tol = 1e-9 if method != "amg-cg" else 1e-8
    assert np.linalg.norm(A @ res.x - b) <= tol * np.linalg.norm(b)
    assert res.iterations >= 1 and res.seconds > 0
    if method == "amg-cg":
        assert res.iterations < 200  # rigid-body near-nullspace keeps SA-AMG CG in the tens


def test_multiple_rhs_and_independent_factorizations(system):
    A, b, _ = system
    f1 = factorize(A)
    f2 = factorize(2.0 * A)  # a second live factorization must not clobber the first (PARDISO memory)
    X = f1.solve(np.c_[b, 3 * b])
    assert X.shape == (A.shape[0], 2)
    # round-off only: same matrix, linear right-hand sides
    assert np.allclose(X[:, 1], 3 * X[:, 0], rtol=1e-10, atol=0)
    assert np.allclose(f2.solve(b), 0.5 * f1.solve(b), rtol=1e-8, atol=0)


def test_unsymmetric_matrix_is_detected():
    n = 200
    A = sp.diags([-1.0, 2.5, -0.5], [-1, 0, 1], shape=(n, n), format="csr")
    fac = factorize(A)
    assert not fac.symmetric and fac.method in ("pardiso", "umfpack", "superlu")
    b = np.ones(n)
    assert np.linalg.norm(A @ fac.solve(b) - b) < 1e-12 * n  # round-off of a well-conditioned system
    with pytest.raises(ValueError, match="symmetric"):
        factorize(A, "amg-cg")


def test_auto_choice_by_size():
    assert choose_method(10, True, iterative_above=5) == "amg-cg"
    assert choose_method(10, False, iterative_above=5) in ("pardiso", "umfpack", "superlu")
    with pytest.raises(ValueError, match="expected one of"):
        choose_method(10, True, "lapack")
