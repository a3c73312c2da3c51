"""Errors of the geometry package."""
from __future__ import annotations

from femcheck.errors import FemcheckError


class MeshingError(FemcheckError, RuntimeError):
    """Meshing of a part failed or gave an invalid mesh; names the part and its parameters.

    Example: ``meshing universal_joint failed (size_m=0.0004, pin_radius_m=0.001, ...): bore radius ...``.
    """

    def __init__(self, part: str, parameters: dict | None, reason: str):
        self.part = part
        self.parameters = dict(parameters or {})
        shown = ", ".join(f"{k}={v}" for k, v in sorted(self.parameters.items()) if not isinstance(v, (dict, list)))
        super().__init__(f"meshing {part} failed ({shown}): {reason}")
