"""Parameters that only the solid (FE) model of the 6-PSU device needs: the optional ``[solid]`` table.

The analytical model never reads these. Every field has a documented default so that a case
written for the analytical model alone still builds meshes.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SolidModel:
    """Solid-model parameters (filled in by the geometry work; all optional, SI)."""
