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

    def result_rows(self, points, columns: dict, ok: np.ndarray, **extra) -> dict:
        """The chunk's result columns (k samples x n points, sample-major): sample id and key, point, the swept
        parameter values (``p:KEY``), the model's ``columns``, ``ok`` and any ``extra`` columns."""
        k, n_pts = self.n_samples, len(points)
        out = {"sample_id": np.repeat(self.sample_ids.astype(np.int64), n_pts),
               "sample_key": np.repeat(np.asarray(self.sample_keys, dtype=object), n_pts),
               "point": np.tile(np.asarray(points, dtype=object), k)}
        for j, key in enumerate(self.keys):
            out[f"p:{key}"] = np.repeat(self.values[:, j], n_pts)
        out.update(columns)
        out["ok"] = ok
        out.update(extra)
        return out
