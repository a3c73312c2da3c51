"""Cross-section properties of the beam elements (docs/conventions.md §5, "Sections").

Local frame: beam axis z; ``Iy = int x^2 dA`` resists bending deflection along x, ``Ix = int y^2 dA``
along y. All inputs may be numpy arrays (broadcast), so that sweeps evaluate many sections at once.

:func:`rectangle_section` and :func:`tube_section` are THE section laws of the analytical model (read from this
module when the parameters are derived; the kernels receive A, Ix, Iy, Jt as parameters).
"""
from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class Section:
    """A beam cross-section. A m^2; Ix, Iy m^4; Jt torsion constant m^4; shear_factor kappa (-)."""

    A: np.ndarray | float
    Ix: np.ndarray | float
    Iy: np.ndarray | float
    Jt: np.ndarray | float
    shear_factor: float


def rectangle_section(b, h) -> Section:
    """Solid rectangle, width ``b`` along local x and depth ``h`` along local y (m).

    ``A = b h``, ``Iy = h b^3 / 12``, ``Ix = b h^3 / 12``; Saint-Venant torsion constant (Roark)
    ``Jt = a c^3 [1/3 - 0.21 (c/a)(1 - c^4 / (12 a^4))]`` with a = max(b, h), c = min(b, h);
    Timoshenko shear factor kappa = 5/6.
    """
    b, h = np.asarray(b, dtype=float), np.asarray(h, dtype=float)
    a, c = np.maximum(b, h), np.minimum(b, h)
    Jt = a * c**3 * (1.0 / 3.0 - 0.21 * (c / a) * (1.0 - c**4 / (12.0 * a**4)))
    return Section(A=b * h, Ix=b * h**3 / 12.0, Iy=h * b**3 / 12.0, Jt=Jt, shear_factor=5.0 / 6.0)


def tube_section(D, d) -> Section:
    """Round tube, outer ``D`` and inner ``d`` diameters (m); d = 0 gives a solid rod.

    ``A = pi (D^2 - d^2) / 4``, ``Ix = Iy = pi (D^4 - d^4) / 64``, ``Jt = 2 Ix``; kappa = 0.5 (thin tube)
    or 0.9 (solid rod, d = 0).
    """
    D, d = np.asarray(D, dtype=float), np.asarray(d, dtype=float)
    I = np.pi * (D**4 - d**4) / 64.0
    kappa = 0.9 if np.all(d == 0) else 0.5
    return Section(A=np.pi * (D**2 - d**2) / 4.0, Ix=I, Iy=I, Jt=2.0 * I, shear_factor=kappa)
