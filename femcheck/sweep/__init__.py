"""Parameter sweeps of the analytical stiffness models: design of experiments, vectorized
evaluation, a resumable Parquet store, local or Dask execution, sensitivity analysis and an HTML
summary.

Modules (one concept each): :mod:`~femcheck.sweep.parameters` (``KEY=LO:HI[:N|log]``),
:mod:`~femcheck.sweep.design` (grid / LHS / Sobol'-Saltelli samples), :mod:`~femcheck.sweep.evaluate_analytical`
(the per-chunk task), :mod:`~femcheck.sweep.store` (Parquet chunks + manifest), :mod:`~femcheck.sweep.executor`
(process pool or Dask), :mod:`~femcheck.sweep.analysis` (stiffness vs parameter, elasticities, Sobol'
indices, contributions, mass), :mod:`~femcheck.sweep.report` (HTML), :mod:`~femcheck.sweep.run` (the
whole sweep, as the CLI runs it). Importing the package does no work.
"""
from __future__ import annotations

__all__ = ["parameters", "design", "evaluate_analytical", "store", "executor", "analysis", "report", "run"]
