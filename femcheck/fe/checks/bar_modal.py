"""``bar-modal``: longitudinal natural frequencies of a bar on a normal contact spring (seed 004 eqs. 29–31).

Bar free at x = 0, on a normal contact spring k_n at x = l: tan(λ l) = β / (λ l), β = k_n l / (E A),
ω_i = λ_i sqrt(E/ρ) (seed 004 eqs. 29–31; the text after eq. 29 says "Eq. 11", a typo for eq. 29).
FE model: a P2 tetrahedral steel bar l = 200 mm, 10 × 10 mm, ν = 0 with the lateral displacements
u_y = u_z = 0 held (the 1-D bar of the seed: uniaxial stress, plane sections), consistent mass, the spring
spread over the end face as the contact-spring matrix K̃_C of seed 004 eq. 44 with k_n / A per unit
area, β = 1. Computed: the 4th natural frequency (the one the mesh resolves worst); the detail lists
all four with their errors.
"""
from __future__ import annotations

import time

import numpy as np
import skfem

from femcheck.fe import constraints
from femcheck.fe.checks import CheckResult
from femcheck.fe.elasticity import assemble_mass, assemble_stiffness, dof_triplets, vector_basis
from femcheck.fe.modal import bar_on_spring_roots, contact_spring_stiffness, natural_frequencies

NAME = "bar-modal"
#: relative error accepted at each mesh level (``femcheck check-solver`` fails above it)
TOLERANCE = {"coarse": 1e-2, "default": 1e-2, "fine": 1e-2}
TOLERANCE_REASON = "P2 bar on a spring: the 4th mode converges as h^4; 0.3 % at the coarse mesh, 1 % flags a wrong mass or spring"
E, RHO, LEN, A_SIDE, BETA, N_MODES = 210e9, 7850.0, 0.200, 0.010, 1.0, 4
MESHES = {"coarse": 6, "default": 12, "fine": 24}


def reference_frequencies(beta: float = BETA, n_modes: int = N_MODES) -> np.ndarray:
    """f_i = λ_i l / l · sqrt(E/ρ) / 2π, Hz (seed 004 eqs. 30–31)."""
    return bar_on_spring_roots(beta, n_modes) / LEN * np.sqrt(E / RHO) / (2 * np.pi)


def bar_frequencies(nx: int, beta: float = BETA, n_modes: int = N_MODES):
    """FE frequencies (Hz) of the bar; returns (frequencies (n_modes,), DOFs)."""
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, LEN, nx + 1), np.linspace(0, A_SIDE, 2), np.linspace(0, A_SIDE, 2))
    basis = vector_basis(mesh, 2)
    K = assemble_stiffness(basis, E, 0.0)
    M = assemble_mass(basis, RHO)
    end = skfem.FacetBasis(mesh, basis.elem, facets=mesh.facets_satisfying(lambda x: np.isclose(x[0], LEN)), intorder=4)
    k_n = beta * E * A_SIDE**2 / LEN
    Kc = contact_spring_stiffness(end, k_n / A_SIDE**2)
    _, trip = dof_triplets(basis)
    c = constraints.clamp(basis.N, trip[:, 1:])
    res = natural_frequencies(c.reduce_matrix(K + Kc), c.reduce_matrix(M), n_modes, shift=0.0)
    return res.frequencies_Hz, basis.N


def run(mesh: str = "default") -> CheckResult:
    t0 = time.perf_counter()
    f, ndof = bar_frequencies(MESHES[mesh])
    ref = reference_frequencies()
    rel = np.abs(f - ref) / ref
    return CheckResult(name=NAME, quantity=f"f_{N_MODES} (Hz), beta = {BETA:g}", computed=float(f[-1]),
                       reference=float(ref[-1]), dofs=ndof, iterations=1, seconds=time.perf_counter() - t0,
                       detail={"frequencies_Hz": f.round(3).tolist(), "reference_Hz": ref.round(3).tolist(),
                               "rel_errors": rel.tolist(), "max_rel_error": float(rel.max())})
