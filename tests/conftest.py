"""Shared fixtures. Tests run from the repository root (pytest's rootdir)."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

ROOT = Path(__file__).resolve().parents[1]
REFERENCE_CASE = ROOT / "cases" / "haptic_6psu.toml"
SHARED_REFERENCE = ROOT.parent / "shared" / "reference" / "haptic_6psu.toml"


@pytest.fixture(scope="session")
def case():
    import femcheck
    return femcheck.load_case(REFERENCE_CASE)


@pytest.fixture(scope="session")
def points(case):
    import femcheck
    return femcheck.test_points(case)


@pytest.fixture(scope="session")
def isolated_mesh_cache(tmp_path_factory):
    """Mesh cache in a temporary folder, so geometry tests neither read nor fill the user's cache."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("FEMCHECK_CACHE", str(tmp_path_factory.mktemp("meshes")))
        yield


def assert_same_tables(t1, t2):
    """Two pyarrow result tables are equal column by column, bit for bit (identical inputs through the same
    deterministic code in any process must give identical results)."""
    import numpy as np
    a = {c: np.asarray(t1.column(c).to_numpy(zero_copy_only=False)) for c in t1.column_names}
    b = {c: np.asarray(t2.column(c).to_numpy(zero_copy_only=False)) for c in t2.column_names}
    assert a.keys() == b.keys()
    for c in a:
        np.testing.assert_array_equal(a[c], b[c], err_msg=c)
