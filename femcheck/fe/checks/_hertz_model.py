"""The two-block contact model that both Hertz problems solve (``hertz-sphere`` and ``hertz-cylinder``).

Specimen: identical steel bodies, E = 210 GPa, ν = 0.3, so Johnson's effective modulus
E* = [(1 − ν₁²)/E₁ + (1 − ν₂²)/E₂]⁻¹ = E / (2 (1 − ν²)) = 115.4 GPa (Johnson §4.2); the indenter (sphere or
cylinder) has radius R = 5 mm, and each body is a block of half-size L = 1.5 mm, joined on z = 0 by
:func:`femcheck.fe.checks._graded_mesh.join` (lower block = master, upper block = slave, from element ``n_lower`` on).

Force control: the upper block's far field moves rigidly with one extra unknown Δ, the last DOF, which carries
the external force; δ = −Δ is then Hertz theory's mutual approach of distant points (Johnson §4.2).
:func:`approach_constraints` writes that as u = T q + g (:class:`femcheck.fe.constraints.Constraints`): the
dependent DOFs are prescribed (symmetry planes, rollers, a far-field displacement), and those of the upper
far field along z follow Δ. :func:`assemble` turns a joined mesh into the :class:`HertzModel` both problems solve.
"""
from __future__ import annotations

import dataclasses
import time
from typing import Callable

import numpy as np

from femcheck.compliance.hertz_point_contact import effective_modulus
from femcheck.fe.checks._graded_mesh import dof_body
from femcheck.fe.constraints import Constraints, clamp, combine, follow
from femcheck.fe.contact.pairing import ContactPair, default_penalty, pair_surfaces
from femcheck.fe.elasticity import assemble_stiffness, vector_basis
from femcheck.fe.newton import ContactProblem

#: Young's modulus (Pa) and Poisson ratio of both bodies (steel)
E, NU = 210e9, 0.3
#: indenter radius (m): the sphere's, or the cylinder's in the plane-strain section
R = 5e-3
#: half-size of each block (m): 13–19 contact radii of the sphere, 14 half-widths of the cylinder
L = 1.5e-3
#: effective modulus E* of the identical pair (Pa), 115.4 GPa
E_STAR = float(effective_modulus(E, NU, E, NU))


@dataclasses.dataclass(frozen=True)
class HertzModel:
    """Assembled contact model: ``problem`` (K, f, constraints, the one contact pair), that ``pair``, the vector
    ``basis``, ``delta_dof`` the index of the approach unknown Δ, ``n_lower`` the number of lower-block elements,
    and the wall times (s) of assembly and meshing."""

    problem: ContactProblem
    pair: ContactPair
    basis: object
    delta_dof: int
    n_lower: int
    assembly_s: float
    mesh_s: float


def contact_facets(mesh, n_lower: int, tol: float, width_y: float = L) -> tuple[np.ndarray, np.ndarray]:
    """(slave, master) boundary facet indices of a joined two-block model: slave = the upper body's bottom (flat
    or curved), master = the lower block's top face z = 0. Facets on the symmetry planes x = 0, y = 0 and on the
    outer faces x = L, y = ``width_y`` (m; L for the quarter sphere model, the slab thickness for the plane-strain
    cylinder) are left out, within ``tol`` (m). The upper body's elements are those from index ``n_lower`` on."""
    bf = mesh.boundary_facets()
    fc = mesh.p[:, mesh.facets[:, bf]].mean(axis=1)
    upper_f = mesh.f2t[0, bf] >= n_lower
    interior = (fc[0] > tol) & (fc[0] < L - tol) & (fc[1] > tol) & (fc[1] < width_y - tol)
    return bf[upper_f & interior & (fc[2] < L - tol)], bf[~upper_f & interior & np.isclose(fc[2], 0.0, atol=tol)]


def approach_constraints(dependent: np.ndarray, on_delta: np.ndarray, delta_dof: int,
                         g: np.ndarray | None = None) -> Constraints:
    """u = T q + g for a model whose last DOF ``delta_dof`` is the approach unknown Δ.

    ``dependent`` (delta_dof,) bool: the constrained mesh DOFs; those in ``on_delta`` (indices: the upper far
    field along z) move with Δ, u = Δ + g (:func:`femcheck.fe.constraints.follow`), the others are prescribed,
    u = g (:func:`femcheck.fe.constraints.clamp`); ``g`` (delta_dof + 1,) the prescribed displacements (m), zero
    when omitted. The free DOFs are the other mesh DOFs and Δ."""
    ndof = delta_dof + 1
    g = np.zeros(ndof) if g is None else g
    fixed = np.setdiff1d(np.flatnonzero(dependent), on_delta)
    return combine(clamp(ndof, fixed, g[fixed]), follow(ndof, on_delta, delta_dof, g[on_delta]))


def assemble(mesh, n_lower: int, constrain: Callable, load_N: float, *, name: str, penalty_factor: float,
             intorder: int = 2, width_y: float = L, initial_gap: Callable | None = None,
             mesh_s: float = 0.0) -> HertzModel:
    """The :class:`HertzModel` of a joined two-block ``mesh`` (P2 vector basis, both bodies E, NU).

    ``constrain(basis, body, delta_dof, tol)`` returns the model's :class:`Constraints` (``body`` (N,) 0 lower /
    1 upper per DOF, ``tol`` m); ``load_N`` is the force on Δ (N; negative pushes the upper block down, the
    model's symmetry share of the load); the frictionless pair ``name`` joins the surfaces of
    :func:`contact_facets` (``width_y``) with the default penalty times ``penalty_factor``; ``initial_gap(points)``
    (m, per slave point (n, 3)) is added to the pair's initial gap where the indenter's profile is not in the mesh;
    ``mesh_s`` is the caller's meshing time (s)."""
    t0 = time.perf_counter()
    basis = vector_basis(mesh, 2)
    K = assemble_stiffness(basis, E, NU)
    body = dof_body(basis, n_lower)
    tol = 1e-9 * L
    delta_dof = basis.N
    C = constrain(basis, body, delta_dof, tol)
    f = np.zeros(basis.N + 1)
    f[delta_dof] = load_N
    slave, master = contact_facets(mesh, n_lower, tol, width_y)
    eps = default_penalty(mesh, slave, E, penalty_factor)
    pair = pair_surfaces(basis, slave, master, penalty_n=eps, friction=0.0, name=name, ndof=basis.N + 1,
                         intorder=intorder)
    if initial_gap is not None:
        pair = dataclasses.replace(pair, g0=pair.g0 + initial_gap(pair.points))
    problem = ContactProblem(K=K, f=f, constraints=C, pairs=(pair,))
    return HertzModel(problem=problem, pair=pair, basis=basis, delta_dof=delta_dof, n_lower=n_lower,
                      assembly_s=time.perf_counter() - t0, mesh_s=mesh_s)
