"""What every sweep task carries: a chunk of samples of the design (picklable; sent to pool or Dask workers)."""
from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class SampleChunk:
    """case: the base case; keys, kinds: swept dotted keys and their kinds ("array" | "variant");
    values: (k, d) parameter values (SI); sample_ids: (k,) int; sample_keys: (k,) result keys.
    Model-specific tasks extend it (``AnalyticalTask``, ``FETask``)."""

    case: object
    keys: tuple[str, ...]
    kinds: tuple[str, ...]
    values: np.ndarray
    sample_ids: np.ndarray
    sample_keys: tuple[str, ...]

    @property
    def n_samples(self) -> int:
        return int(self.values.shape[0])
