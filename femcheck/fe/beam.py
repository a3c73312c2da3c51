"""3D two-node beam elements (12 DOF): Euler–Bernoulli with optional Timoshenko shear.

Local frame per element: local **z is the beam axis** (node 1 → node 2, the convention of the analytical
models), local x is the component of the element's ``orientation`` vector normal to the axis (default:
global X, or global Y when the axis is within 1e-6 of X), local y = z × x. ``R`` (3 × 3) has the local unit
vectors as rows, so v_local = R v_global.

DOFs per node: (u_x, u_y, u_z, θ_x, θ_y, θ_z) in m and rad, node k at ``dof_offset + 6k + (0..5)``.

Local stiffness (Przemieniecki, *Theory of Matrix Structural Analysis*, §5.6; Timoshenko shear via
Φ = 12 E I / (κ G A L²)):

* axial  EA/L [[1, −1], [−1, 1]] on u_z;   torsion  GJ/L [[1, −1], [−1, 1]] on θ_z;
* bending in the x–z plane (u_x, θ_y; u_x' = θ_y) with E I_y, I_y = ∫ x² dA, and in the y–z plane
  (u_y, θ_x; u_y' = −θ_x) with E I_x, I_x = ∫ y² dA, each
  EI / (L³ (1 + Φ)) · [[12, 6L, −12, 6L], [6L, (4+Φ)L², −6L, (2−Φ)L²], [−12, −6L, 12, −6L], [6L, (2−Φ)L², −6L, (4+Φ)L²]].

This element is exact at the nodes for end loads (a cantilever with a tip load gives
δ = P L³ / (3 E I) + P L / (κ G A) with any number of elements). Consistent mass: axial/torsion
ρAL/6 and ρI_pL/6 [[2, 1], [1, 2]], bending the Euler–Bernoulli cubic ρAL/420 matrix (no rotary inertia).
Global matrices K_g = Tᵀ K_l T with T = diag(R, R, R, R), vectorized over elements (numpy einsum) and
assembled with scipy.sparse.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.sparse as sp


@dataclasses.dataclass(frozen=True)
class BeamSection:
    """Cross-section constants (SI): area ``A`` m², second moments ``Ix`` = ∫y² dA and ``Iy`` = ∫x² dA m⁴
    (x, y local section axes), torsion constant ``J`` m⁴, shear coefficients ``kappa_x`` / ``kappa_y``
    (shear area κA for shear along local x / y)."""

    A: float
    Ix: float
    Iy: float
    J: float
    kappa_x: float = 5.0 / 6.0
    kappa_y: float = 5.0 / 6.0

    @classmethod
    def rectangle(cls, width_x: float, height_y: float, nu: float = 0.3) -> "BeamSection":
        """Solid rectangle width_x (along local x) × height_y (along local y), m. κ from Cowper (1966)
        10(1+ν)/(12+11ν); J from Roark: a b³ [1/3 − 0.21 (b/a)(1 − b⁴/(12 a⁴))], a ≥ b."""
        a, b = max(width_x, height_y), min(width_x, height_y)
        J = a * b**3 * (1.0 / 3.0 - 0.21 * (b / a) * (1.0 - b**4 / (12.0 * a**4)))
        k = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)
        return cls(A=width_x * height_y, Ix=width_x * height_y**3 / 12.0, Iy=height_y * width_x**3 / 12.0,
                   J=J, kappa_x=k, kappa_y=k)

    @classmethod
    def circle(cls, diameter: float, nu: float = 0.3) -> "BeamSection":
        """Solid circle, m. κ from Cowper: 6(1+ν)/(7+6ν); J = π d⁴/32."""
        I = math.pi * diameter**4 / 64.0
        k = 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu)
        return cls(A=math.pi * diameter**2 / 4.0, Ix=I, Iy=I, J=2.0 * I, kappa_x=k, kappa_y=k)

    @classmethod
    def tube(cls, outer_diameter: float, inner_diameter: float, nu: float = 0.3) -> "BeamSection":
        """Circular tube, m. κ from Cowper for thin/thick tubes with m = d_i/d_o:
        6(1+ν)(1+m²)² / ((7+6ν)(1+m²)² + (20+12ν) m²)."""
        do, di = outer_diameter, inner_diameter
        if not 0.0 <= di < do:
            raise ValueError(f"tube needs 0 <= inner_diameter < outer_diameter, got {di}, {do}")
        I = math.pi * (do**4 - di**4) / 64.0
        m2 = (di / do) ** 2
        k = 6.0 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)
        return cls(A=math.pi * (do**2 - di**2) / 4.0, Ix=I, Iy=I, J=2.0 * I, kappa_x=k, kappa_y=k)


def element_axes(nodes, elements, what: str) -> tuple[np.ndarray, np.ndarray]:
    """(unit axis vectors node 1 -> node 2 (ne, 3), lengths (ne,) m) of the two-node line elements ``elements``
    (ne, 2) between ``nodes`` (n, 3) m; a zero-length element is refused, naming ``what`` and its indices."""
    nodes = np.asarray(nodes, dtype=float)
    elements = np.asarray(elements, dtype=np.int64).reshape(-1, 2)
    d = nodes[elements[:, 1]] - nodes[elements[:, 0]]
    L = np.linalg.norm(d, axis=1)
    if np.any(L <= 0):
        raise ValueError(f"{what} of zero length: element(s) {np.flatnonzero(L <= 0)[:10].tolist()}")
    return d / L[:, None], L


def local_frames(nodes, elements, orientation=None):
    """Rotation matrices R (ne, 3, 3) (rows = local x, y, z in global coordinates) and lengths L (ne,) m.

    nodes (n, 3) m; elements (ne, 2) int; orientation (3,) or (ne, 3): a vector whose component normal to
    the axis becomes local x.
    """
    ez, L = element_axes(nodes, elements, "beam element")
    if orientation is None:
        ref = np.tile([1.0, 0.0, 0.0], (len(L), 1))
        par = np.abs(ez[:, 0]) > 1.0 - 1e-6
        ref[par] = [0.0, 1.0, 0.0]
    else:
        ref = np.broadcast_to(np.asarray(orientation, dtype=float), ez.shape).copy()
    ex = ref - np.einsum("ij,ij->i", ref, ez)[:, None] * ez
    nx = np.linalg.norm(ex, axis=1)
    if np.any(nx < 1e-9):
        raise ValueError("beam orientation vector parallel to the element axis for element(s) "
                         f"{np.flatnonzero(nx < 1e-9)[:10].tolist()}")
    ex /= nx[:, None]
    ey = np.cross(ez, ex)
    return np.stack([ex, ey, ez], axis=1), L


def _bending_block(EI, L, phi):
    """(ne, 4, 4) bending stiffness for (v1, θ1, v2, θ2) with v' = θ (see module docstring)."""
    c = EI / (L**3 * (1.0 + phi))
    k = np.empty((len(L), 4, 4))
    L2 = L * L
    k[:, 0] = np.stack([12 + 0 * L, 6 * L, -12 + 0 * L, 6 * L], 1)
    k[:, 1] = np.stack([6 * L, (4 + phi) * L2, -6 * L, (2 - phi) * L2], 1)
    k[:, 2] = np.stack([-12 + 0 * L, -6 * L, 12 + 0 * L, -6 * L], 1)
    k[:, 3] = np.stack([6 * L, (2 - phi) * L2, -6 * L, (4 + phi) * L2], 1)
    return c[:, None, None] * k


def _bending_mass_block(mL, L):
    """(ne, 4, 4) consistent Euler–Bernoulli mass for (v1, θ1, v2, θ2), mL = ρ A L."""
    m = np.empty((len(L), 4, 4))
    L2 = L * L
    m[:, 0] = np.stack([156 + 0 * L, 22 * L, 54 + 0 * L, -13 * L], 1)
    m[:, 1] = np.stack([22 * L, 4 * L2, 13 * L, -3 * L2], 1)
    m[:, 2] = np.stack([54 + 0 * L, 13 * L, 156 + 0 * L, -22 * L], 1)
    m[:, 3] = np.stack([-13 * L, -3 * L2, -22 * L, 4 * L2], 1)
    return (mL / 420.0)[:, None, None] * m


# local DOF indices of the two bending planes and their rotation signs (v' = θ_y in x–z, v' = −θ_x in y–z)
_XZ = np.array([0, 4, 6, 10])
_YZ = np.array([1, 3, 7, 9])
_S_XZ = np.array([1.0, 1.0, 1.0, 1.0])
_S_YZ = np.array([1.0, -1.0, 1.0, -1.0])


def _place(K, idx, block, sign):
    K[:, idx[:, None], idx[None, :]] += block * (sign[:, None] * sign[None, :])


def _per_elem(v, ne, name):
    a = np.asarray(v, dtype=float)
    a = np.broadcast_to(a, (ne,)) if a.ndim == 0 or a.shape == (ne,) else None
    if a is None:
        raise ValueError(f"{name} must be a scalar or one value per element ({ne},)")
    return np.asarray(a, dtype=float)


def local_stiffness(L, E, G, section: BeamSection, shear: bool = True) -> np.ndarray:
    """Local element stiffness (ne, 12, 12), N/m, N/rad, N·m/rad (module docstring)."""
    L = np.asarray(L, dtype=float)
    ne = L.size
    E, G = _per_elem(E, ne, "E"), _per_elem(G, ne, "G")
    A, Ix, Iy, J = (_per_elem(getattr(section, k), ne, k) for k in ("A", "Ix", "Iy", "J"))
    K = np.zeros((ne, 12, 12))
    ka = E * A / L
    kt = G * J / L
    for i, j, k in ((2, 8, ka), (5, 11, kt)):
        K[:, i, i] += k
        K[:, j, j] += k
        K[:, i, j] -= k
        K[:, j, i] -= k
    if shear:
        phi_xz = 12.0 * E * Iy / (_per_elem(section.kappa_x, ne, "kappa_x") * G * A * L**2)
        phi_yz = 12.0 * E * Ix / (_per_elem(section.kappa_y, ne, "kappa_y") * G * A * L**2)
    else:
        phi_xz = phi_yz = np.zeros(ne)
    _place(K, _XZ, _bending_block(E * Iy, L, phi_xz), _S_XZ)
    _place(K, _YZ, _bending_block(E * Ix, L, phi_yz), _S_YZ)
    return K


def local_mass(L, density, section: BeamSection) -> np.ndarray:
    """Local consistent mass (ne, 12, 12), kg and kg·m² (module docstring)."""
    L = np.asarray(L, dtype=float)
    ne = L.size
    rho = _per_elem(density, ne, "density")
    A = _per_elem(section.A, ne, "A")
    Ip = _per_elem(section.Ix, ne, "Ix") + _per_elem(section.Iy, ne, "Iy")
    M = np.zeros((ne, 12, 12))
    for (i, j), mm in (((2, 8), rho * A * L), ((5, 11), rho * Ip * L)):
        M[:, i, i] += mm / 3.0
        M[:, j, j] += mm / 3.0
        M[:, i, j] += mm / 6.0
        M[:, j, i] += mm / 6.0
    blk = _bending_mass_block(rho * A * L, L)
    _place(M, _XZ, blk, _S_XZ)
    _place(M, _YZ, blk, _S_YZ)
    return M


def _to_global(Kl, R):
    T = np.zeros((len(R), 12, 12))
    for b in range(4):
        T[:, 3 * b:3 * b + 3, 3 * b:3 * b + 3] = R
    return np.einsum("eji,ejk,ekl->eil", T, Kl, T)


def beam_dofs(node_ids, dof_offset: int = 0) -> np.ndarray:
    """Global DOF indices (n, 6) of beam nodes: dof_offset + 6·node + (0..5)."""
    return dof_offset + 6 * np.asarray(node_ids, dtype=np.int64).reshape(-1, 1) + np.arange(6)


def _assemble(Ke, elements, ndof, dof_offset):
    elements = np.asarray(elements, dtype=np.int64).reshape(-1, 2)
    dofs = beam_dofs(elements.ravel(), dof_offset).reshape(-1, 12)
    rows = np.repeat(dofs, 12, axis=1).ravel()
    cols = np.tile(dofs, (1, 12)).ravel()
    return sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(ndof, ndof))


def assemble_beam_stiffness(nodes, elements, E, G, section: BeamSection, orientation=None, shear: bool = True,
                            ndof: int | None = None, dof_offset: int = 0) -> sp.csr_matrix:
    """Global stiffness (ndof × ndof, csr) of beam elements; ndof defaults to dof_offset + 6·n_nodes.

    nodes (n, 3) m; elements (ne, 2); E, G Pa (scalar or per element); ``shear=False`` gives Euler–Bernoulli.
    """
    R, L = local_frames(nodes, elements, orientation)
    ndof = dof_offset + 6 * len(nodes) if ndof is None else ndof
    return _assemble(_to_global(local_stiffness(L, E, G, section, shear), R), elements, ndof, dof_offset)


def assemble_beam_mass(nodes, elements, density, section: BeamSection, orientation=None,
                       ndof: int | None = None, dof_offset: int = 0) -> sp.csr_matrix:
    """Global consistent mass (ndof × ndof, csr) of beam elements; density kg/m³."""
    R, L = local_frames(nodes, elements, orientation)
    ndof = dof_offset + 6 * len(nodes) if ndof is None else ndof
    return _assemble(_to_global(local_mass(L, density, section), R), elements, ndof, dof_offset)


def line_mesh(start, end, n_elements: int):
    """Straight beam from ``start`` to ``end`` (m) in n_elements: nodes (n+1, 3), elements (n, 2)."""
    s = np.linspace(0.0, 1.0, n_elements + 1)[:, None]
    nodes = (1 - s) * np.asarray(start, dtype=float) + s * np.asarray(end, dtype=float)
    elements = np.c_[np.arange(n_elements), np.arange(1, n_elements + 1)]
    return nodes, elements
