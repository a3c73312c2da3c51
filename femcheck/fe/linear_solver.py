"""Sparse linear solvers for the FE equations K u = f, chosen automatically by size and availability.

Three paths:

* ``"pardiso"`` — Intel MKL PARDISO through :mod:`pypardiso` (direct, multithreaded). Symmetric matrices are
  factorized as real symmetric indefinite (``mtype=-2``, Bunch–Kaufman LDLᵀ, upper triangle only), others as
  real unsymmetric (``mtype=11``; friction makes the contact tangent unsymmetric).
* ``"cholmod"`` — SuiteSparse CHOLMOD supernodal Cholesky LLᵀ through :mod:`cvxopt` (a pip wheel with no
  system libraries on Linux, macOS and Windows, x86-64 and ARM), for symmetric positive definite matrices.
  An unsymmetric matrix (frictional contact tangent) or one that turns out not positive definite is
  factorized with UMFPACK (unsymmetric multifrontal LU) from the same wheel instead, with a log line.
* ``"umfpack"`` — SuiteSparse UMFPACK LU through :mod:`cvxopt`, any nonsingular matrix.
* ``"mumps"`` — MUMPS through the ``python-mumps`` package (``import mumps``) when it is installed;
  otherwise selecting it is a one-line error naming the package to install.
* ``"superlu"`` (alias ``"splu"``) — scipy's SuperLU (direct, single-threaded, slow above ~20k unknowns:
  measured 20–77× PARDISO on the 82k-unknown Hertz system). Used only when asked for, or by ``"auto"``
  when neither pypardiso nor cvxopt imports — then with a warning naming what to install.

``"auto"``: PARDISO where MKL exists, else CHOLMOD for symmetric matrices (UMFPACK for
unsymmetric ones), else SuperLU with a warning. The process-wide choice that replaces ``"auto"`` comes from
:func:`set_preferred` (the CLI ``--linear-solver`` option, a case file's ``[solver] linear``) or the
environment variable ``FEMCHECK_LINEAR_SOLVER``; :func:`methods_used` lists which solvers actually ran
(the manifest records it).
* ``"amg-cg"`` — conjugate gradients preconditioned by one V-cycle of pyamg smoothed aggregation, for
  symmetric positive definite systems above ``iterative_above`` unknowns, where a direct factorization
  would need too much memory. Pass the rigid-body modes as ``near_nullspace`` for elasticity
  (:func:`femcheck.fe.elasticity.rigid_body_modes`) — the aggregation then converges in tens of iterations.

A :class:`Factorization` is made once and reused for many right-hand sides (modified Newton–Raphson keeps
it within a load step, seed 004 §3.3). Each Factorization owns its own PARDISO instance, so two live
factorizations never overwrite each other's internal memory.
"""
from __future__ import annotations

import dataclasses
import functools
import logging
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

log = logging.getLogger(__name__)

METHODS = ("auto", "pardiso", "cholmod", "umfpack", "mumps", "superlu", "splu", "amg-cg")
#: the values of a case file's ``[solver] linear`` and of ``--linear-solver``
CHOICES = ("auto", "pardiso", "cholmod", "mumps", "superlu", "umfpack")
ENV_VAR = "FEMCHECK_LINEAR_SOLVER"
_preferred: str | None = None
_used: dict[str, int] = {}
#: above this many unknowns "auto" takes the iterative path (if the matrix is symmetric)
ITERATIVE_ABOVE = 400_000


#: pypardiso looks for MKL's runtime library on every solver it creates (ctypes' find_library, then a recursive
#: glob over the whole environment: measured 1.6 s per solver on a 2.4 GB venv under load, 44 solvers = 71 s of a
#: 103 s contact solve); once found, its path is handed on through this variable (worker processes inherit it)
MKL_RT_VAR = "PYPARDISO_MKL_RT"


@functools.lru_cache(maxsize=1)
def pardiso_available() -> bool:
    """True when pypardiso imports and finds MKL (checked lazily, never at import of this module). Also records
    the library's path in ``$PYPARDISO_MKL_RT`` (:data:`MKL_RT_VAR`), so later solvers do not search for it."""
    import os
    if os.environ.get("FEMCHECK_NO_PARDISO", "").strip() in ("1", "true", "yes"):
        return False   # MKL hidden on purpose: the path of machines without it (ARM), e.g. to measure it
    try:
        import pypardiso  # noqa: F401
        solver = pypardiso.PyPardisoSolver()
    except Exception:  # ImportError, or OSError when mkl_rt is missing
        return False
    path = getattr(solver.libmkl, "_name", None)
    if path:   # a full path (found by the glob) or a soname that the loader resolves (found by find_library)
        os.environ.setdefault(MKL_RT_VAR, path)
    return True


@functools.lru_cache(maxsize=1)
def cvxopt_available() -> bool:
    """True when cvxopt (CHOLMOD + UMFPACK) imports."""
    try:
        import cvxopt.cholmod  # noqa: F401
        import cvxopt.umfpack  # noqa: F401
    except Exception:
        return False
    return True


def mumps_available() -> bool:
    """True when python-mumps (the ``mumps`` module with ``Context``; not PyMUMPS's) imports."""
    try:
        import mumps
    except Exception:
        return False
    return hasattr(mumps, "Context")


def set_preferred(name: str | None) -> None:
    """Make ``name`` what ``"auto"`` means for the rest of the process (None: back to the automatic
    choice). Raises :class:`femcheck.errors.FemcheckError` naming the expected values."""
    import os
    global _preferred
    if name is not None:
        name = _check_choice(name, "linear solver")
    _preferred = None if name in (None, "auto") else name
    if _preferred is not None:  # worker processes (--jobs) inherit the choice through the environment
        os.environ[ENV_VAR] = _preferred


def preferred() -> str:
    """The explicit choice in force: :func:`set_preferred`, else ``$FEMCHECK_LINEAR_SOLVER``, else "auto"."""
    import os
    if _preferred is not None:
        return _preferred
    env = os.environ.get(ENV_VAR, "").strip()
    return _check_choice(env, f"environment variable {ENV_VAR}") if env else "auto"


def _check_choice(name: str, where: str) -> str:
    name = str(name).strip().lower()
    if name == "splu":
        name = "superlu"
    if name not in CHOICES:
        from femcheck.errors import FemcheckError
        raise FemcheckError(f"{where} = {name!r}; expected one of {', '.join(CHOICES)}")
    return name


def describe() -> dict:
    """What the manifest records: the choice in force, what "auto" resolves to here for a symmetric and
    an unsymmetric system, and the factorizations made in this process by solver."""
    choice = preferred()
    return {"choice": choice,
            "symmetric": choose_method(1, True, choice), "unsymmetric": choose_method(1, False, choice),
            "factorizations_in_process": methods_used()}


def methods_used() -> dict[str, int]:
    """Factorizations made in this process, by the solver that actually ran (e.g. ``{"cholmod": 3}``)."""
    return dict(_used)


def is_symmetric(A, rtol: float = 1e-10) -> bool:
    """max|A − Aᵀ| ≤ rtol · max|A| (one pass over the nonzeros)."""
    A = sp.csr_matrix(A)
    if A.nnz == 0:
        return True
    d = A - A.T
    return (abs(d).max() if d.nnz else 0.0) <= rtol * abs(A).max()


def choose_method(n: int, symmetric: bool, method: str = "auto", iterative_above: int = ITERATIVE_ABOVE) -> str:
    """The method "auto" resolves to for an ``n × n`` matrix (see module docstring)."""
    if method not in METHODS:
        raise ValueError(f"linear solver method = {method!r}; expected one of {', '.join(METHODS)}")
    if method == "splu":
        method = "superlu"
    if method == "auto":
        method = preferred()
    if method != "auto":
        if method == "pardiso" and not pardiso_available():
            from femcheck.errors import FemcheckError
            raise FemcheckError("linear solver 'pardiso' needs Intel MKL: pip install pypardiso (x86-64 only)")
        if method in ("cholmod", "umfpack") and not cvxopt_available():
            from femcheck.errors import FemcheckError
            raise FemcheckError(f"linear solver {method!r} needs cvxopt: pip install cvxopt")
        if method == "mumps" and not mumps_available():
            from femcheck.errors import FemcheckError
            raise FemcheckError("linear solver 'mumps' needs python-mumps: pip install python-mumps "
                                "(or conda install -c conda-forge python-mumps)")
        if method == "cholmod" and not symmetric:
            return "umfpack"
        return method
    if symmetric and n > iterative_above:
        return "amg-cg"
    if pardiso_available():
        return "pardiso"
    if cvxopt_available():
        return "cholmod" if symmetric else "umfpack"
    _warn_superlu()
    return "superlu"


@functools.lru_cache(maxsize=1)
def _warn_superlu() -> None:
    log.warning("no fast sparse solver found: using scipy SuperLU (20-77x slower than PARDISO above 40k "
                "unknowns); install cvxopt (pip install cvxopt: CHOLMOD/UMFPACK, every platform) or "
                "pypardiso (x86-64 with MKL)")


class Factorization:
    """A reusable solver for one sparse square matrix A (n × n, float64).

    Attributes: ``method`` ("pardiso" | "splu" | "amg-cg"), ``seconds`` (wall time of the factorization
    or AMG setup, s), ``n`` (unknowns), ``symmetric``, ``iterations`` (CG iterations of the last solve;
    1 for direct methods). ``solve(b)`` accepts b of shape (n,) or (n, k) and returns x of the same shape.
    """

    def __init__(self, A, method: str = "auto", *, symmetric: bool | None = None,
                 iterative_above: int = ITERATIVE_ABOVE, near_nullspace=None, rtol: float = 1e-10,
                 maxiter: int = 2000):
        A = sp.csr_matrix(A, dtype=np.float64)
        if A.shape[0] != A.shape[1]:
            raise ValueError(f"matrix must be square, got shape {A.shape}")
        A.sum_duplicates()
        A.sort_indices()
        self.n = A.shape[0]
        self.symmetric = is_symmetric(A) if symmetric is None else bool(symmetric)
        self.method = choose_method(self.n, self.symmetric, method, iterative_above)
        if self.method == "amg-cg" and not self.symmetric:
            raise ValueError("amg-cg needs a symmetric positive definite matrix; use 'pardiso' or 'splu'")
        self.iterations = 0
        self._rtol, self._maxiter = rtol, maxiter
        t0 = time.perf_counter()
        if self.method == "pardiso":
            import pypardiso
            if self.symmetric:
                self._solver = pypardiso.PyPardisoSolver(mtype=-2)
                self._A = sp.triu(A, format="csr")
                self._A.sort_indices()
            else:
                self._solver = pypardiso.PyPardisoSolver(mtype=11)
                self._A = A
            self._solver.factorize(self._A)
        elif self.method == "cholmod":
            try:
                self._F = _cholmod_factor(A)
            except ArithmeticError:  # not positive definite: LU from the same library
                log.info("CHOLMOD: matrix not positive definite; factorizing with UMFPACK instead")
                self.method = "umfpack"
                self._cvA, self._F = _umfpack_factor(A)
        elif self.method == "umfpack":
            self._cvA, self._F = _umfpack_factor(A)
        elif self.method == "mumps":
            import mumps
            self._ctx = mumps.Context()
            self._ctx.factor(A.tocoo(), ordering="auto")
        elif self.method == "superlu":
            self._lu = spla.splu(A.tocsc(), permc_spec="COLAMD" if not self.symmetric else "MMD_AT_PLUS_A")
        else:
            import pyamg
            B = None if near_nullspace is None else np.asarray(near_nullspace, dtype=float)
            self._A = A
            self._ml = pyamg.smoothed_aggregation_solver(A, B=B, symmetry="symmetric", max_coarse=500)
            self._M = self._ml.aspreconditioner(cycle="V")
        self.seconds = time.perf_counter() - t0
        _used[self.method] = _used.get(self.method, 0) + 1
        log.info("factorized %d x %d (nnz %d, symmetric=%s) with %s in %.3f s",
                 self.n, self.n, A.nnz, self.symmetric, self.method, self.seconds)

    def solve(self, b) -> np.ndarray:
        """x with A x = b; b: (n,) or (n, k) float."""
        b = np.asarray(b, dtype=np.float64)
        if b.shape[0] != self.n:
            raise ValueError(f"right-hand side has {b.shape[0]} rows; the matrix has {self.n}")
        if self.method == "pardiso":
            x = self._solver.solve(self._A, b)
            self.iterations = 1
            return np.asarray(x).reshape(b.shape)
        if self.method == "superlu":
            self.iterations = 1
            return self._lu.solve(b)
        if self.method in ("cholmod", "umfpack"):
            import cvxopt
            B = cvxopt.matrix(np.asfortranarray(b.reshape(self.n, -1)))
            if self.method == "cholmod":
                import cvxopt.cholmod
                cvxopt.cholmod.solve(self._F, B)
            else:
                import cvxopt.umfpack
                cvxopt.umfpack.solve(self._cvA, self._F, B)
            self.iterations = 1
            return np.array(B).reshape(b.shape)
        if self.method == "mumps":
            self.iterations = 1
            cols = b.reshape(self.n, -1)
            return np.column_stack([self._ctx.solve(cols[:, j]) for j in range(cols.shape[1])]).reshape(b.shape)
        cols = b.reshape(self.n, -1)
        out = np.empty_like(cols)
        its = 0
        for j in range(cols.shape[1]):
            count = [0]

            def cb(_xk, count=count):
                count[0] += 1
            x, info = spla.cg(self._A, cols[:, j], rtol=self._rtol, atol=0.0, maxiter=self._maxiter,
                              M=self._M, callback=cb)
            if info != 0:
                from femcheck.errors import ConvergenceError
                raise ConvergenceError(f"AMG-preconditioned CG did not reach rtol={self._rtol:g} in "
                                       f"{self._maxiter} iterations (n={self.n})", detail={"info": info})
            out[:, j] = x
            its = max(its, count[0])
        self.iterations = its
        return out.reshape(b.shape)

    def free(self) -> None:
        """Release the solver's memory now. PARDISO keeps its factors in memory that Python does not own:
        without this, every renewed factorization of a Newton loop stays allocated until the process ends
        (measured: > 14 GB after ~20 factorizations of a 40k-unknown frictional contact model)."""
        solver = getattr(self, "_solver", None)
        if solver is not None:
            solver.free_memory(everything=True)
            self._solver = None

    def __del__(self):
        try:
            self.free()
        except Exception:  # interpreter shutdown: the library may already be gone
            pass

    def __repr__(self) -> str:
        return f"Factorization(n={self.n}, method={self.method!r}, seconds={self.seconds:.3g})"


def _cvxopt_sparse(A):
    import cvxopt
    c = A.tocoo()
    return cvxopt.spmatrix(c.data.astype(float), c.row.astype(int), c.col.astype(int), c.shape)


def _cholmod_factor(A):
    """Supernodal LLᵀ of the lower triangle of symmetric A (CHOLMOD picks AMD/METIS ordering)."""
    import cvxopt.cholmod
    cvxopt.cholmod.options["supernodal"] = 2
    cvxopt.cholmod.options["postorder"] = True
    L = _cvxopt_sparse(sp.tril(A, format="csr"))
    F = cvxopt.cholmod.symbolic(L, uplo="L")
    cvxopt.cholmod.numeric(L, F)
    return F


def _umfpack_factor(A):
    import cvxopt.umfpack
    M = _cvxopt_sparse(A)
    return M, cvxopt.umfpack.numeric(M, cvxopt.umfpack.symbolic(M))


def factorize(A, method: str = "auto", **kwargs) -> Factorization:
    """Factorize (or set up the preconditioner for) sparse A; see :class:`Factorization` for ``kwargs``."""
    return Factorization(A, method, **kwargs)


@dataclasses.dataclass(frozen=True)
class SolveResult:
    """``x`` (n,) or (n, k); ``method`` used; ``seconds`` total wall time (factorization + solve);
    ``iterations`` (CG iterations, 1 for direct); ``factor_seconds`` / ``solve_seconds`` split."""

    x: np.ndarray
    method: str
    seconds: float
    iterations: int
    factor_seconds: float = 0.0
    solve_seconds: float = 0.0


def solve(A, b, method: str = "auto", **kwargs) -> SolveResult:
    """Solve A x = b once (factorize + solve); ``kwargs`` as for :class:`Factorization`."""
    fac = Factorization(A, method, **kwargs)
    t0 = time.perf_counter()
    x = fac.solve(b)
    ts = time.perf_counter() - t0
    return SolveResult(x=x, method=fac.method, seconds=fac.seconds + ts, iterations=fac.iterations,
                       factor_seconds=fac.seconds, solve_seconds=ts)
