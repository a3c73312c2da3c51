"""On-disk mesh cache keyed by the part parameters and the code version, so sweeps do not re-mesh.

Key = sha256 of the canonical JSON of {part, parameters, code version}; the code version is a hash of
the source of the ``geometry`` package plus the pytetwild / numpy versions, so any change of the
meshing code invalidates old entries. Folder: ``$FEMCHECK_CACHE`` if set, else
``.femcheck-cache/meshes`` in the current directory. Entries are ``<key>.npz`` written atomically.
"""
from __future__ import annotations

import functools
import hashlib
import io
import json
import logging
import os
from pathlib import Path

import numpy as np

from femcheck.report.atomic import write_bytes_atomic

log = logging.getLogger(__name__)


@functools.lru_cache(maxsize=1)
def code_version() -> str:
    """Hash of the geometry package source and the versions of the meshing libraries."""
    h = hashlib.sha256()
    pkg = Path(__file__).parent
    for f in sorted(pkg.glob("*.py")):
        h.update(f.name.encode())
        h.update(f.read_bytes())
    for mod in ("pytetwild", "numpy", "trimesh"):
        try:
            h.update(f"{mod}={__import__(mod).__version__}".encode())
        except Exception:  # pragma: no cover
            h.update(f"{mod}=?".encode())
    return h.hexdigest()[:16]


def cache_key(part: str, parameters: dict) -> str:
    """sha256 (hex, 32 chars) of {part, parameters, code version}."""
    blob = json.dumps({"part": part, "parameters": parameters, "code": code_version()}, sort_keys=True, default=_jsonable)
    return hashlib.sha256(blob.encode()).hexdigest()[:32]


def _jsonable(v):
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    raise TypeError(f"not JSON-able: {type(v).__name__}")


def cache_dir() -> Path:
    return Path(os.environ.get("FEMCHECK_CACHE") or Path.cwd() / ".femcheck-cache" / "meshes")


def load(key: str):
    """The cached PartMesh for ``key`` or None."""
    path = cache_dir() / f"{key}.npz"
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            return _from_arrays(dict(z))
    except Exception as exc:  # a corrupt entry is re-meshed, never trusted
        log.warning("ignoring unreadable mesh cache entry %s: %s", path, exc)
        return None


def store(mesh) -> Path:
    """Write ``mesh`` under its cache key (atomically)."""
    buf = io.BytesIO()
    np.savez_compressed(buf, **_to_arrays(mesh))
    path = write_bytes_atomic(cache_dir() / f"{mesh.cache_key}.npz", buf.getvalue())
    log.debug("stored mesh %s", path)
    return path


def _to_arrays(mesh) -> dict:
    regions = {}
    arrays = {"points": mesh.points, "tets": mesh.tets, "body_of_tet": mesh.body_of_tet}
    for i, (name, r) in enumerate(mesh.regions.items()):
        arrays[f"r{i}_facets"], arrays[f"r{i}_nodes"], arrays[f"r{i}_normals"] = r.facets, r.nodes, r.normals
        regions[name] = {"i": i, "kind": r.kind, "pair": r.pair, "side": r.side, "doc": r.doc,
                         "reference_point": None if r.reference_point is None else r.reference_point.tolist()}
    meta = {"part": mesh.part, "bodies": [[b.name, b.material, b.analytic_volume_m3] for b in mesh.bodies],
            "regions": regions, "parameters": dict(mesh.parameters), "quality": dict(mesh.quality), "cache_key": mesh.cache_key}
    arrays["meta"] = np.frombuffer(json.dumps(meta, default=_jsonable).encode(), dtype=np.uint8)
    return arrays


def _from_arrays(z: dict):
    from geometry.part_mesh import Body, PartMesh, Region
    meta = json.loads(bytes(z["meta"]).decode())
    regions = {}
    for name, r in meta["regions"].items():
        i = r["i"]
        regions[name] = Region(name=name, kind=r["kind"], facets=z[f"r{i}_facets"], nodes=z[f"r{i}_nodes"],
                               normals=z[f"r{i}_normals"], reference_point=r["reference_point"], pair=r["pair"],
                               side=r["side"], doc=r["doc"])
    return PartMesh(part=meta["part"], points=z["points"], tets=z["tets"], body_of_tet=z["body_of_tet"],
                    bodies=tuple(Body(*b) for b in meta["bodies"]), regions=regions, parameters=meta["parameters"],
                    quality=meta["quality"], cache_key=meta["cache_key"])
