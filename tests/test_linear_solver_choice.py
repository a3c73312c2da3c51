"""Issue 17 item 1: the sparse solver is chosen explicitly ([solver] linear, --linear-solver,
FEMCHECK_LINEAR_SOLVER), "auto" never falls silently to SuperLU, and every backend solves the same
elasticity and frictional-contact-like (unsymmetric) systems to round-off."""
import logging

import numpy as np
import pytest
import scipy.sparse as sp

from conftest import clamped_steel_bar
from femcheck.errors import FemcheckError
from femcheck.fe import linear_solver as ls

needs_cvxopt = pytest.mark.skipif(not ls.cvxopt_available(), reason="cvxopt (CHOLMOD/UMFPACK) not installed")


@pytest.fixture(autouse=True)
def _reset(monkeypatch):
    monkeypatch.delenv(ls.ENV_VAR, raising=False)
    ls.set_preferred(None)
    yield
    ls.set_preferred(None)


@pytest.fixture(scope="module")
def elastic():
    basis, K, c = clamped_steel_bar(11, 4, 1)
    return c.reduce_matrix(K), np.random.default_rng(3).standard_normal(c.free.size)


@needs_cvxopt
def test_cholmod_matches_superlu_on_spd_and_falls_to_lu_when_unsymmetric(elastic):
    K, b = elastic
    x_ref = ls.solve(K, b, "superlu").x
    fac = ls.factorize(K, "cholmod", symmetric=True)
    assert fac.method == "cholmod"
    # both direct: agree to round-off of a system with condition ~1e6
    assert np.linalg.norm(fac.solve(b) - x_ref) <= 1e-9 * np.linalg.norm(x_ref)
    # friction makes the tangent unsymmetric: a skew part of 10 % of the diagonal
    n = K.shape[0]
    skew = sp.diags(0.1 * K.diagonal()[:-1], 1, shape=(n, n))
    A = (K + skew - skew.T).tocsr()
    fac = ls.factorize(A, "cholmod")
    assert fac.method == "umfpack"  # CHOLMOD cannot factor it; LU from the same wheel
    assert np.linalg.norm(A @ fac.solve(b) - b) <= 1e-9 * np.linalg.norm(b)  # round-off


@needs_cvxopt
def test_cholmod_on_indefinite_matrix_falls_back_to_umfpack():
    n = 50
    A = sp.diags(np.r_[np.ones(n - 1), -1.0], 0, format="csr")  # symmetric, one negative pivot
    fac = ls.factorize(A, "cholmod", symmetric=True)
    assert fac.method == "umfpack"
    assert np.allclose(fac.solve(np.ones(n)), np.r_[np.ones(n - 1), -1.0])


def test_preference_order_cli_case_env(monkeypatch):
    from femcheck.case.solver_options import SolverOptions, apply

    class Case:
        solver = SolverOptions(linear="superlu")

    monkeypatch.setenv(ls.ENV_VAR, "pardiso")
    assert ls.preferred() == "pardiso"  # environment alone
    assert apply(Case()) == "superlu"  # the case file beats the environment
    assert apply(Case(), cli_choice="cholmod") == "cholmod"  # the command line beats the case file
    assert apply(Case()) == "cholmod"  # and stays in force for the process
    assert ls.choose_method(10, False) == ("umfpack" if ls.cvxopt_available() else "superlu")


def test_bad_names_are_one_line_errors(monkeypatch):
    with pytest.raises(FemcheckError, match="expected one of auto, pardiso, cholmod, mumps, superlu"):
        ls.set_preferred("lapack")
    monkeypatch.setenv(ls.ENV_VAR, "fast")
    with pytest.raises(FemcheckError, match="FEMCHECK_LINEAR_SOLVER"):
        ls.preferred()


def test_case_file_key_is_validated(tmp_path):
    from femcheck.case import load_case
    src = open("cases/haptic_6psu.toml", "rb").read().decode()
    p = tmp_path / "c.toml"
    p.write_text(src + '\n[solver]\nlinear = "cholmod"\n')
    assert load_case(p).solver.linear == "cholmod"
    p.write_text(src + '\n[solver]\nlinear = "gauss"\n')
    with pytest.raises(FemcheckError, match=r"solver\.linear.*expected one of"):
        load_case(p)


def test_auto_without_fast_solvers_warns_naming_the_package(monkeypatch, caplog):
    monkeypatch.setattr(ls, "pardiso_available", lambda: False)
    monkeypatch.setattr(ls, "cvxopt_available", lambda: False)
    ls._warn_superlu.cache_clear()
    with caplog.at_level(logging.WARNING, logger="femcheck.fe.linear_solver"):
        assert ls.choose_method(100, True) == "superlu"
    assert "pip install cvxopt" in caplog.text


def test_unavailable_choice_names_what_to_install(monkeypatch):
    monkeypatch.setattr(ls, "mumps_available", lambda: False)
    with pytest.raises(FemcheckError, match="pip install python-mumps"):
        ls.choose_method(10, True, "mumps")


def test_cli_root_option_sets_choice():
    from typer.testing import CliRunner
    from femcheck.cli import get_app
    r = CliRunner().invoke(get_app(), ["--linear-solver", "superlu", "--help"])
    assert r.exit_code == 0
    r = CliRunner().invoke(get_app(), ["--linear-solver", "gauss", "check-solver", "--help"])
    assert r.exit_code != 0
