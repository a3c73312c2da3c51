"""Columnar result store of a sweep: Parquet chunks + a JSON manifest, resumable.

Layout of the output folder::

    manifest.json              case hash, parameter ranges, design, versions, timing, status
    design.parquet             the samples (sample_id, block, base, p:<key> ...)
    chunks/chunk-<first sample>-<digest>.parquet
                               rows (sample, point) of one finished task
    results.parquet            all rows, sorted by sample and point (written when the sweep completes)

Every file is written atomically (temporary file + rename, :mod:`femcheck.report.atomic`), and each
finished task is its own chunk file, written as soon as the task returns. Ctrl-C or a crashed worker
therefore loses at most the tasks still running; a chunk on disk is always complete. Each row carries
the ``sample_key``: a SHA-256 of the case content, the code version, the model options and the exact
parameter values (:func:`sample_keys`), so ``--resume`` skips exactly the samples whose results exist
and never mixes in results of a different case, model or code.
"""
from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import io
import json
import logging
import platform
from pathlib import Path

import numpy as np

from femcheck.report.atomic import write_bytes_atomic, write_text_atomic

log = logging.getLogger(__name__)

#: source folders/files whose content defines the analytical results (part of the code version)
_MODEL_SOURCES = ("chain", "compliance", "kinematics", "case/schema.py", "case/registry.py", "case/parallel_device.py",
                  "case/psu_layout.py", "case/device_options.py",
                  "case/haptic_6psu_solid.py", "sweep/evaluate_analytical.py")


def source_hash(root: Path, entries) -> str:
    """SHA-256 (12 hex) of the ``*.py`` files (path and content) of ``entries`` (files or folders below ``root``)."""
    h = hashlib.sha256()
    for entry in entries:
        p = root / entry
        for f in sorted([p] if p.is_file() else p.rglob("*.py")):
            h.update(str(f.relative_to(root)).encode())
            h.update(f.read_bytes())
    return h.hexdigest()[:12]


@functools.lru_cache(maxsize=1)
def code_version() -> str:
    """``femcheck <version>+<12 hex>``: the package version and a hash of the model source files."""
    import femcheck
    return f"{femcheck.__version__}+{source_hash(Path(femcheck.__file__).parent, _MODEL_SOURCES)}"


def sample_keys(case_sha256: str, keys, values: np.ndarray, options: dict, version: str | None = None) -> list[str]:
    """One result key per sample: SHA-256 (32 hex) of case hash, code version, options, keys and the
    exact float bits of the sample's values (``values`` (m, d))."""
    head = json.dumps({"case": case_sha256, "code": version or code_version(), "options": options,
                       "keys": list(keys)}, sort_keys=True).encode()
    values = np.ascontiguousarray(values, dtype=np.float64)
    return [hashlib.sha256(head + row.tobytes()).hexdigest()[:32] for row in values]


def software_versions() -> dict[str, str]:
    """Versions of Python and of the libraries the sweep depends on."""
    out = {"python": platform.python_version()}
    for dist in ("femcheck", "numpy", "scipy", "numba", "pyarrow", "dask", "distributed", "matplotlib"):
        try:
            out[dist] = importlib.metadata.version(dist)
        except importlib.metadata.PackageNotFoundError:
            out[dist] = "not installed"
    return out


def _table(columns: dict):
    import pyarrow as pa
    arrays = {}
    for name, v in columns.items():
        v = np.asarray(v)
        arrays[name] = pa.array(v.tolist() if v.dtype == object else v)
    return pa.table(arrays)


def _parquet_bytes(table) -> bytes:
    import pyarrow.parquet as pq
    buf = io.BytesIO()
    pq.write_table(table, buf)
    return buf.getvalue()


class SweepStore:
    """The output folder of one sweep (see the module docstring)."""

    def __init__(self, out_dir):
        self.root = Path(out_dir)
        self.chunks_dir = self.root / "chunks"
        self.manifest_path = self.root / "manifest.json"
        self.design_path = self.root / "design.parquet"
        self.results_path = self.root / "results.parquet"

    # -- chunks ---------------------------------------------------------------------------------
    def chunk_files(self) -> list[Path]:
        """Finished chunk files (temporary files of interrupted writes are not listed)."""
        return sorted(self.chunks_dir.glob("chunk-*.parquet")) if self.chunks_dir.is_dir() else []

    def has_results(self) -> bool:
        return bool(self.chunk_files())

    def finished_keys(self) -> set[str]:
        """Sample keys of every finished chunk."""
        import pyarrow.parquet as pq
        done: set[str] = set()
        for f in self.chunk_files():
            done.update(pq.read_table(f, columns=["sample_key"]).column("sample_key").unique().to_pylist())
        return done

    def write_chunk(self, columns: dict) -> Path:
        """Write one finished task's rows atomically; returns the chunk path."""
        table = _table(columns)
        first = int(np.min(columns["sample_id"])) if len(columns["sample_id"]) else 0
        digest = hashlib.sha256("".join(sorted(set(columns["sample_key"]))).encode()).hexdigest()[:12]
        path = self.chunks_dir / f"chunk-{first:09d}-{digest}.parquet"
        write_bytes_atomic(path, _parquet_bytes(table))
        log.debug("wrote %s (%d rows)", path, table.num_rows)
        return path

    def read_results(self, keys: set[str] | None = None):
        """All finished rows (a pyarrow Table) whose sample_key is in ``keys`` (None: all), sorted by
        sample_id and the order the points were written in."""
        import pyarrow as pa
        import pyarrow.compute as pc
        import pyarrow.parquet as pq
        tables, seen = [], set()
        for f in self.chunk_files():
            t = pq.read_table(f)
            file_keys = set(t.column("sample_key").unique().to_pylist())
            wanted = (file_keys if keys is None else file_keys & keys) - seen
            if wanted != file_keys:  # other sweeps' rows, or a sample already read from another chunk
                t = t.filter(pc.is_in(t.column("sample_key"), value_set=pa.array(sorted(wanted), pa.string())))
            seen |= wanted
            tables.append(t)
        if not tables:
            return None
        t = pa.concat_tables(tables, promote_options="default")
        # stable sort by sample_id keeps each sample's points in the order they were written
        return t.take(pa.array(np.argsort(t.column("sample_id").to_numpy(), kind="stable")))

    def results_for(self, sample_keys: list[str], n_points: int):
        """The result table of a design: for sample i of ``sample_keys`` its ``n_points`` stored rows,
        in design order, with ``sample_id`` = i (a resumed sweep may have stored the same values under
        other ids, e.g. a longer Sobol' sequence). None if any sample has no stored result."""
        import pyarrow as pa
        t = self.read_results(set(sample_keys))
        if t is None:
            return None
        keys = t.column("sample_key").to_pylist()
        first = {}
        for row in range(0, len(keys), n_points):  # rows of a sample are contiguous (one per point)
            first.setdefault(keys[row], row)
        missing = [k for k in sample_keys if k not in first]
        if missing:
            return None
        rows = (np.array([first[k] for k in sample_keys])[:, None] + np.arange(n_points)).ravel()
        t = t.take(pa.array(rows))
        ids = np.repeat(np.arange(len(sample_keys), dtype=np.int64), n_points)
        return t.set_column(t.column_names.index("sample_id"), "sample_id", pa.array(ids))

    # -- design, manifest, final table ----------------------------------------------------------
    def write_design(self, columns: dict) -> None:
        write_bytes_atomic(self.design_path, _parquet_bytes(_table(columns)))

    def write_results(self, table) -> Path:
        write_bytes_atomic(self.results_path, _parquet_bytes(table))
        return self.results_path

    def read_manifest(self) -> dict | None:
        if not self.manifest_path.is_file():
            return None
        return json.loads(self.manifest_path.read_text(encoding="utf-8"))

    def write_manifest(self, manifest: dict) -> None:
        write_text_atomic(self.manifest_path, json.dumps(manifest, indent=2, default=_json_default) + "\n")


def _json_default(o):
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    return str(o)
