"""Designs of experiments over the parameter box (scipy.stats.qmc), reproducible with a seed.

- ``grid``: full factorial of each parameter's levels (``KEY=LO:HI:N``; default ``--samples`` levels
  per parameter, else :data:`~femcheck.sweep.parameters.DEFAULT_GRID_LEVELS`); m = prod N_j samples.
- ``lhs``: Latin hypercube (``qmc.LatinHypercube``), m = ``samples``.
- ``sobol``: Saltelli's scheme for variance-based sensitivity (Saltelli et al. 2010, Comput. Phys.
  Commun. 181:259): a scrambled Sobol' sequence in 2d dimensions gives the base matrices A and B
  (n x d each, n = ``samples`` rounded up to a power of 2); AB_i is A with column i taken from B.
  m = n (d + 2) samples, in blocks A, B, AB_0, ..., AB_{d-1}.

Samples are in the parameters' SI units (log ranges are uniform in ln p).
"""
from __future__ import annotations

import dataclasses
import itertools
import logging

import numpy as np
from scipy.stats import qmc

from femcheck.errors import CaseError
from femcheck.sweep.parameters import DEFAULT_GRID_LEVELS, ParameterRange

log = logging.getLogger(__name__)

DESIGNS = ("grid", "lhs", "sobol")
#: block numbers of the Saltelli design: A, B, then AB_i = BLOCK_AB + i
BLOCK_A, BLOCK_B, BLOCK_AB = 0, 1, 2


@dataclasses.dataclass(frozen=True)
class Design:
    """Samples of a sweep.

    kind: "grid" | "lhs" | "sobol"; values: (m, d) parameter values (SI); block: (m,) int, the
    Saltelli block (sobol) or 0; base: (m,) int, row of the base matrix (sobol) or the sample index;
    n_base: n of the Saltelli design (sobol) or m; levels: per-parameter levels (grid) or None; seed.
    """

    kind: str
    values: np.ndarray
    block: np.ndarray
    base: np.ndarray
    n_base: int
    levels: tuple[int, ...] | None
    seed: int

    @property
    def m(self) -> int:
        return int(self.values.shape[0])


def make_design(ranges: list[ParameterRange], kind: str = "lhs", samples: int | None = None, seed: int = 0) -> Design:
    """Build the design ``kind`` over ``ranges`` (see the module docstring for the sample counts)."""
    d = len(ranges)
    if kind == "grid":
        levels = tuple(r.levels or samples or DEFAULT_GRID_LEVELS for r in ranges)
        axes = [r.grid(n) for r, n in zip(ranges, levels)]
        values = np.array(list(itertools.product(*axes)), dtype=float).reshape(-1, d)
        m = values.shape[0]
        return Design(kind, values, np.zeros(m, int), np.arange(m), m, levels, seed)
    if kind == "lhs":
        m = int(samples or 64)
        if m < 2:
            raise CaseError("--samples", str(samples), "an LHS design needs at least 2 samples")
        u = qmc.LatinHypercube(d=d, rng=np.random.default_rng(seed)).random(m)
        values = np.column_stack([r.from_unit(u[:, j]) for j, r in enumerate(ranges)])
        return Design(kind, values, np.zeros(m, int), np.arange(m), m, None, seed)
    if kind == "sobol":
        n_req = int(samples or 64)
        if n_req < 2:
            raise CaseError("--samples", str(samples), "a Sobol' design needs at least 2 base samples")
        n = 1 << (n_req - 1).bit_length()
        if n != n_req:
            log.warning("sobol design: base sample count %d rounded up to the power of 2 %d", n_req, n)
        u = qmc.Sobol(d=2 * d, scramble=True, rng=np.random.default_rng(seed)).random(n)
        A, B = u[:, :d], u[:, d:]
        blocks = [A, B]
        for i in range(d):
            AB = A.copy()
            AB[:, i] = B[:, i]
            blocks.append(AB)
        uu = np.concatenate(blocks)
        values = np.column_stack([r.from_unit(uu[:, j]) for j, r in enumerate(ranges)])
        block = np.repeat(np.arange(d + 2), n)
        base = np.tile(np.arange(n), d + 2)
        return Design(kind, values, block, base, n, None, seed)
    raise CaseError("--design", kind, f"unknown design; expected one of {list(DESIGNS)}")
