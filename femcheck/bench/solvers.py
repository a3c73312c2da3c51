"""Bench ``solvers``: every available sparse direct solver on three of femcheck's own systems,
the same matrix and right-hand side for each — factorization + solve wall time and relative residual
‖A x − b‖/‖b‖, each also as a ratio to the best solver on that system.

Systems (the matrices the FE code really factorizes, captured at the :func:`femcheck.fe.linear_solver.factorize`
call of the model):

* ``cantilever_p2_36k`` — the P2 solid cantilever of check ``cantilever-solid`` at 50 × 5 × 5 cells
  (clamped, reduced stiffness; symmetric positive definite), 36.7k unknowns;
* ``hertz_42k`` / ``hertz_82k`` — the Hertz sphere check (:mod:`femcheck.fe.checks.hertz_sphere`, default and
  fine level): the first iteration matrix of the modified Newton loop, reduced stiffness + contact penalty
  springs of the initially closed points (symmetric positive definite; frictionless).

Solvers: ``pardiso`` (if MKL), ``cholmod`` and ``umfpack`` (cvxopt), ``mumps`` (if python-mumps), ``superlu``
(scipy; skipped above ``SUPERLU_MAX_DOFS`` unknowns unless ``FEMCHECK_BENCH_SUPERLU=1``, because it takes
minutes there: measured 20–77× PARDISO at 82k). Keys: ``<system>_<solver>_s``, ``_residual``,
``_time_ratio`` (to the fastest), ``<system>_dofs``, ``<system>_fastest``.
"""
from __future__ import annotations

import os
import time

import numpy as np

from femcheck.fe import linear_solver as ls

AREA = "solvers"
SUPERLU_MAX_DOFS = 45_000


class _Captured(Exception):
    def __init__(self, A, symmetric):
        super().__init__("captured")
        self.A, self.symmetric = A, symmetric


def _capture(module, call):
    """Run ``call()`` until ``module.factorize`` is first called; return (A, symmetric) it was given."""
    orig = module.factorize

    def grab(A, method="auto", symmetric=None, **_kw):
        raise _Captured(A, ls.is_symmetric(A) if symmetric is None else symmetric)
    module.factorize = grab
    try:
        call()
    except _Captured as c:
        return c.A, c.symmetric
    finally:
        module.factorize = orig
    raise RuntimeError("the model never factorized a matrix")


def systems():
    """{name: (A, symmetric)} — built lazily, one at a time (each Hertz model needs ~1–3 GB)."""
    import femcheck.fe.checks.cantilever_solid as cs
    import femcheck.fe.checks.hertz_sphere as hs
    import femcheck.fe.newton as newton
    yield "cantilever_p2_36k", _capture(cs, lambda: cs.solve_cantilever(50, 5))
    for name, level in (("hertz_42k", "default"), ("hertz_82k", "fine")):
        model = hs.build(level)
        yield name, _capture(newton, lambda: hs.solve(model))
        del model


def available() -> list[str]:
    out = []
    if ls.pardiso_available():
        out.append("pardiso")
    if ls.cvxopt_available():
        out += ["cholmod", "umfpack"]
    if ls.mumps_available():
        out.append("mumps")
    return out + ["superlu"]


def run() -> dict:
    out: dict = {"solvers_available": ",".join(available())}
    rng = np.random.default_rng(17)
    for name, (A, symmetric) in systems():
        n = A.shape[0]
        b = A @ rng.standard_normal(n)
        out[f"{name}_dofs"] = int(n)
        times = {}
        for method in available():
            if method == "superlu" and n > SUPERLU_MAX_DOFS and os.environ.get("FEMCHECK_BENCH_SUPERLU") != "1":
                continue
            t0 = time.perf_counter()
            fac = ls.factorize(A, method, symmetric=symmetric)
            x = fac.solve(b)
            times[method] = time.perf_counter() - t0
            fac.free()
            out[f"{name}_{method}_s"] = round(times[method], 4)
            out[f"{name}_{method}_residual"] = float(np.linalg.norm(A @ x - b) / np.linalg.norm(b))
            del fac, x
        best = min(times, key=times.get)
        out[f"{name}_fastest"] = best
        for method, t in times.items():
            out[f"{name}_{method}_time_ratio"] = round(t / times[best], 3)
        best_res = min(out[f"{name}_{m}_residual"] for m in times)
        for method in times:
            out[f"{name}_{method}_residual_ratio"] = round(out[f"{name}_{method}_residual"] / max(best_res, 1e-300), 3)
    return out


def table(figures: dict) -> str:
    """Markdown table: per system, time and residual of each solver as ratios to the best."""
    names = [k[:-5] for k in figures if k.endswith("_dofs")]
    rows = ["| system | DOF | solver | time (s) | time / best | residual | residual / best |", "|---|---|---|---|---|---|---|"]
    for s in names:
        for m in ("pardiso", "cholmod", "umfpack", "mumps", "superlu"):
            if f"{s}_{m}_s" in figures:
                rows.append(f"| {s} | {figures[s + '_dofs']} | {m} | {figures[f'{s}_{m}_s']:.3f} | "
                            f"{figures[f'{s}_{m}_time_ratio']:.2f}× | {figures[f'{s}_{m}_residual']:.1e} | "
                            f"{figures[f'{s}_{m}_residual_ratio']:.2g}× |")
    return "\n".join(rows)


if __name__ == "__main__":
    from femcheck.bench.__main__ import print_figures
    print_figures(run(), table)
