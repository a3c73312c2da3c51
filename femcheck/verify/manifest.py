"""Run manifest: what produced a report (case hash, package versions, timings, machine)."""
from __future__ import annotations

import datetime
import importlib.metadata as md
import os
import platform

PACKAGES = ("femcheck", "numpy", "scipy", "cvxopt", "pypardiso", "numba", "scikit-fem", "pytetwild", "trimesh", "meshio", "pyvista", "matplotlib")


def package_versions() -> dict[str, str]:
    out = {}
    for p in PACKAGES:
        try:
            out[p] = md.version(p)
        except md.PackageNotFoundError:
            out[p] = "not installed"
    return out


def base_manifest(case, command: str) -> dict:
    return {
        "command": command,
        "created_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "case": case.source,
        "case_sha256": case.sha256,
        "case_name": case.meta.name,
        "packages": package_versions(),
        "python": platform.python_version(),
        "machine": {"platform": platform.platform(), "cpus": os.cpu_count()},
        "linear_solver": __import__("femcheck.fe.linear_solver", fromlist=["describe"]).describe(),
    }
