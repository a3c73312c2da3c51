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
