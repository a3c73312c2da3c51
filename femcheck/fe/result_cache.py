"""FE results on disk, keyed by everything they are computed from, so a second run of the same case reads them.

An entry's key is the sha256 of its kind, its inputs (JSON: numbers, strings, the ``repr`` of frozen case
sections) and the hash of the source of the FE code that computes it (:func:`fe_code_version`: the packages
``femcheck.fe``, ``femcheck.fe_device`` and ``geometry``, and the linear solver in force), so a change of any
input or of that code gives a new key: an old entry is never read as current, it is only left unused. Entries
are pickles written atomically (a crash leaves no half-written entry); an unreadable entry is computed again.
Folder: ``<cache>/<kind>/<key>.pkl`` under :func:`geometry.cache.cache_dir` (``$FEMCHECK_CACHE``, else
``.femcheck-cache/meshes`` in the current directory); ``FEMCHECK_NO_RESULT_CACHE=1`` turns reading and writing off.
"""
from __future__ import annotations

import functools
import hashlib
import json
import logging
import os
import pickle
from pathlib import Path

log = logging.getLogger(__name__)

ENV_OFF = "FEMCHECK_NO_RESULT_CACHE"


@functools.lru_cache(maxsize=1)
def _source_hash() -> str:
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for pkg in (root / "fe", root / "fe_device", root.parent / "geometry"):
        for f in sorted(pkg.rglob("*.py")):
            h.update(str(f.relative_to(root.parent)).encode())
            h.update(f.read_bytes())
    return h.hexdigest()


def fe_code_version() -> str:
    """Hash of the FE source (module doc) and of the linear solver choice in force (round-off differs)."""
    from femcheck.fe.linear_solver import pardiso_available, preferred
    return hashlib.sha256(f"{_source_hash()}|{preferred()}|{pardiso_available()}".encode()).hexdigest()[:24]


def enabled() -> bool:
    return os.environ.get(ENV_OFF, "").strip() not in ("1", "true", "yes")


def result_key(kind: str, inputs: dict) -> str:
    """The key of a result of ``kind`` computed from ``inputs`` by the current FE code."""
    blob = json.dumps({"kind": kind, "inputs": inputs, "code": fe_code_version()}, sort_keys=True, default=repr)
    return hashlib.sha256(blob.encode()).hexdigest()[:32]


def _path(kind: str, key: str) -> Path:
    from geometry.cache import cache_dir
    return cache_dir() / kind / f"{key}.pkl"


def has(kind: str, key: str) -> bool:
    """Whether an entry exists (for predicting a run's cost; :func:`load` still decides whether it is readable)."""
    return enabled() and _path(kind, key).is_file()


def load(kind: str, key: str):
    """The stored result or None (absent, unreadable, or the cache turned off)."""
    if not enabled():
        return None
    path = _path(kind, key)
    if not path.is_file():
        return None
    try:
        with open(path, "rb") as fh:
            return pickle.load(fh)
    except Exception as exc:  # a corrupt or incompatible entry is computed again, never trusted
        log.warning("ignoring unreadable %s cache entry %s: %s", kind, path, exc)
        return None


def store(kind: str, key: str, value) -> None:
    """Write ``value`` under ``key`` atomically; a read-only cache only costs the next run the computation."""
    if not enabled():
        return
    from femcheck.report.atomic import write_bytes_atomic
    try:
        write_bytes_atomic(_path(kind, key), pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL))
    except OSError as exc:
        log.warning("could not write the %s cache %s: %s", kind, _path(kind, key), exc)
