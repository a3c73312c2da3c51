"""FE model of a rectangular block on contact springs (seed 004 §4.3, eqs. 37–44), on scikit-fem.

Physics. The block (edges a x b x h along x, y, z, corner at the origin) is linear elastic; its mass
and stiffness matrices are seed 004 eqs. 39–40,

    M = int_V rho N^T N dV,        K = int_V B^T D B dV,

assembled with ``skfem.models.elasticity.linear_elasticity`` (hexahedral Q1 or Q2 elements). A
contact face is a layer of distributed springs to a fixed ground; its stiffness matrix is eq. 44

    K_C = int_{S_c} N^T D_c N dS,     D_c = (k_n / A_c) n n^T + (k_t / A_c) (I - n n^T),

where k_n, k_t (N/m) are the total normal and tangential stiffnesses of one contact patch of nominal
area A_c (so k / A_c is the stiffness per unit area, N/m^3). K_C is assembled with unit per-area
stiffness (``contact_matrices``) so that a sweep over k only scales precomputed matrices. "Stuck"
normal contact (seed 004: "the normal contact stiffness becomes infinity") is a Dirichlet condition
u . n = 0 on the patch. The eigenproblem (K + K_C) phi = omega^2 M phi is solved with
:func:`femcheck.fe.modal.natural_frequencies`.

Faces are named ``x-``, ``x+``, ``y-``, ``y+``, ``z-``, ``z+``; a patch is an axis-aligned rectangle
on a face given by its centre and size; mesh lines are placed on patch edges so that the patch is
resolved exactly.
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementHex1, ElementHex2, ElementVector, FacetBasis, MeshHex, asm
from skfem.helpers import dot
from skfem.models.elasticity import linear_elasticity

from femcheck.contact_id.bar_on_spring import ContactIdError
from femcheck.fe.elasticity import lame
from femcheck.fe.modal import ModalResult, natural_frequencies

log = logging.getLogger(__name__)

ELEMENTS = {"hex1": ElementHex1, "hex2": ElementHex2}
#: Gauss order: 2 (hex1) / 4 (hex2) integrate the mass matrix exactly on boxes; higher orders only
#: slow scikit-fem down (it loops over local basis pairs)
INTORDER = {"hex1": 2, "hex2": 4}
FACES = {"x-": (0, 0), "x+": (0, 1), "y-": (1, 0), "y+": (1, 1), "z-": (2, 0), "z+": (2, 1)}


def mass_form(density_kg_m3: float) -> BilinearForm:
    """rho u . v (seed 004 eq. 39)."""
    @BilinearForm
    def mass(u, v, w):
        return density_kg_m3 * dot(u, v)
    return mass


def normal_spring_form() -> BilinearForm:
    """(u . n)(v . n): normal part of eq. 44 per unit area stiffness."""
    @BilinearForm
    def normal(u, v, w):
        return dot(u, w.n) * dot(v, w.n)
    return normal


def tangential_spring_form() -> BilinearForm:
    """u . v - (u . n)(v . n): tangential part of eq. 44 (isotropic in the face, k_t = k_tau, seed 004 §3)."""
    @BilinearForm
    def tangential(u, v, w):
        return dot(u, v) - dot(u, w.n) * dot(v, w.n)
    return tangential


@dataclasses.dataclass(frozen=True)
class Patch:
    """Rectangle on ``face`` (``x-`` ... ``z+``): ``center_m`` and ``size_m`` are the two in-face
    coordinates in axis order (e.g. (x, y) on ``z+``), m. ``size_m = None`` means the whole face."""

    face: str
    center_m: tuple[float, float] | None = None
    size_m: tuple[float, float] | None = None


@dataclasses.dataclass(frozen=True)
class BlockFE:
    """Assembled block: ``basis`` (vector H1), ``K`` elastic stiffness (N/m), ``M`` mass (kg), both
    (ndof, ndof) sparse; ``dims_m`` (a, b, h)."""

    dims_m: tuple[float, float, float]
    element: str
    basis: Basis
    K: sp.csr_matrix
    M: sp.csr_matrix

    @property
    def mesh(self) -> MeshHex:
        return self.basis.mesh

    @property
    def ndof(self) -> int:
        return self.basis.N


def _axis_nodes(length: float, n: int, cuts) -> np.ndarray:
    """About ``n`` divisions of [0, length], always containing the points ``cuts``."""
    base = np.linspace(0.0, length, n + 1)
    pts = np.unique(np.concatenate([base, [c for c in cuts if 0 < c < length]]))
    # drop nodes closer than 20 % of the spacing to a cut (keep cuts), avoiding slivers
    h = length / n
    keep = [p for p in pts if p in cuts or p in (0.0, length) or min(abs(p - c) for c in list(cuts) + [0.0, length]) > 0.2 * h]
    return np.unique(np.array(keep))


def _patch_bounds(dims, patch: Patch) -> tuple[int, int, list[tuple[int, float, float]]]:
    if patch.face not in FACES:
        raise ContactIdError(f"face {patch.face!r}; expected one of {sorted(FACES)}")
    axis, side = FACES[patch.face]
    others = [i for i in range(3) if i != axis]
    bounds = []
    for j, ax in enumerate(others):
        if patch.size_m is None:
            lo, hi = 0.0, dims[ax]
        else:
            c = dims[ax] / 2 if patch.center_m is None else patch.center_m[j]
            lo, hi = c - patch.size_m[j] / 2, c + patch.size_m[j] / 2
            if lo < -1e-12 * dims[ax] or hi > dims[ax] * (1 + 1e-12) or hi <= lo:
                raise ContactIdError(f"contact patch on {patch.face} spans [{lo:.6g}, {hi:.6g}] m along axis {ax}; "
                                     f"expected inside [0, {dims[ax]:.6g}] m")
        bounds.append((ax, lo, hi))
    return axis, side, bounds


def assemble_block(dims_m, divisions, E_Pa: float, nu: float, density_kg_m3: float, element: str = "hex2",
                   patches: tuple[Patch, ...] = ()) -> BlockFE:
    """Mesh the block ``dims_m`` (a, b, h) m with about ``divisions`` (nx, ny, nz) hexahedra (extra
    lines on the edges of ``patches``) and assemble K (eq. 40) and M (eq. 39)."""
    dims = tuple(float(d) for d in dims_m)
    if len(dims) != 3 or min(dims) <= 0:
        raise ContactIdError(f"block dimensions {dims_m}; expected three lengths > 0 m")
    if element not in ELEMENTS:
        raise ContactIdError(f"element {element!r}; expected one of {sorted(ELEMENTS)}")
    div = tuple(int(n) for n in divisions)
    if len(div) != 3 or min(div) < 1:
        raise ContactIdError(f"divisions {divisions}; expected three integers >= 1")
    cuts: list[list[float]] = [[], [], []]
    for p in patches:
        _, _, bounds = _patch_bounds(dims, p)
        for ax, lo, hi in bounds:
            cuts[ax] += [lo, hi]
    axes = [_axis_nodes(dims[i], div[i], cuts[i]) for i in range(3)]
    mesh = MeshHex.init_tensor(*axes)
    basis = Basis(mesh, ElementVector(ELEMENTS[element]()), intorder=INTORDER[element])
    lam, mu = (float(v) for v in lame(E_Pa, nu))  # the one Lamé conversion (femcheck.fe.elasticity)
    K = asm(linear_elasticity(lam, mu), basis).tocsr()
    M = asm(mass_form(density_kg_m3), basis).tocsr()
    log.debug("block %s m, %d elements (%s), %d dofs", dims, mesh.nelements, element, basis.N)
    return BlockFE(dims_m=dims, element=element, basis=basis, K=K, M=M)


def patch_facets(block: BlockFE, patch: Patch) -> np.ndarray:
    """Boundary facet indices of ``patch`` (facet midpoints inside the rectangle)."""
    axis, side, bounds = _patch_bounds(block.dims_m, patch)
    target = block.dims_m[axis] * side
    tol = 1e-9 * max(block.dims_m)

    def inside(x):
        ok = np.abs(x[axis] - target) < tol
        for ax, lo, hi in bounds:
            ok &= (x[ax] > lo - tol) & (x[ax] < hi + tol)
        return ok

    facets = block.mesh.facets_satisfying(inside, boundaries_only=True)
    if facets.size == 0:
        raise ContactIdError(f"contact patch on {patch.face} contains no mesh facet")
    return facets


def patch_area_m2(block: BlockFE, patch: Patch) -> float:
    """Area of the meshed patch (sum of facet areas), m^2."""
    fb = _facet_basis(block, patch_facets(block, patch))
    return float(asm(_area_form(), fb))


def _facet_basis(block: BlockFE, facets) -> FacetBasis:
    return FacetBasis(block.mesh, block.basis.elem, facets=facets, intorder=INTORDER[block.element])


def _area_form():
    from skfem import Functional

    @Functional
    def area(w):
        return 1.0 + 0.0 * w.x[0]
    return area


def contact_matrices(block: BlockFE, patches) -> tuple[sp.csr_matrix, sp.csr_matrix, float]:
    """(K_n1, K_t1, A_c): eq. 44 with unit per-area normal / tangential stiffness, summed over
    ``patches``; A_c the area of one patch (all patches must have the same area). Per-patch total
    stiffnesses k_n, k_t enter as K_C = (k_n / A_c) K_n1 + (k_t / A_c) K_t1."""
    Kn = sp.csr_matrix((block.ndof, block.ndof))
    Kt = sp.csr_matrix((block.ndof, block.ndof))
    areas = []
    for p in patches:
        fb = _facet_basis(block, patch_facets(block, p))
        Kn = Kn + asm(normal_spring_form(), fb)
        Kt = Kt + asm(tangential_spring_form(), fb)
        areas.append(float(asm(_area_form(), fb)))
    if not areas:
        raise ContactIdError("no contact patch given")
    if max(areas) - min(areas) > 1e-9 * max(areas):
        raise ContactIdError(f"contact patch areas {areas} m^2 differ; expected equal patches")
    return Kn.tocsr(), Kt.tocsr(), areas[0]


def component_dofs(block: BlockFE, facets: np.ndarray, component: int) -> np.ndarray:
    """DOF indices of displacement component ``component`` (0, 1, 2 = x, y, z) on ``facets``."""
    return np.asarray(block.basis.get_dofs(facets).all([f"u^{component + 1}"]), dtype=int)


def solve_modes(K, M, fixed_dofs, n_modes: int, shift: float = 0.0) -> ModalResult:
    """Natural frequencies of (K, M) with ``fixed_dofs`` removed; modes are expanded back to all DOFs
    (zeros on fixed DOFs), mass-normalized."""
    n = K.shape[0]
    free = np.setdiff1d(np.arange(n), np.asarray(fixed_dofs, dtype=int))
    Kf = sp.csr_matrix(K)[free][:, free]
    Mf = sp.csr_matrix(M)[free][:, free]
    res = natural_frequencies(Kf, Mf, n_modes, shift=shift)
    modes = np.zeros((n, res.modes.shape[1]))
    modes[free] = res.modes
    return ModalResult(frequencies_Hz=res.frequencies_Hz, modes=modes)
