"""Super-elements of the two flexible parts of a leg: the guideway bar and the proximal-link tube.

A part is meshed in its own local frame (geometry package: guideway frame A_i, origin at the clamp A, z
along the rail; link frame B_i, origin at the ball centre B, z along the link, docs/conventions.md §2),
discretized with P2 tetrahedra (``femcheck.fe.elasticity``) and tied to 6-DOF reference nodes by rigid
couplings (RBE2, ``femcheck.fe.constraints.rigid_coupling``) on its end faces:

* guideway: face z = 0 clamped (the rail clamp at A_i), face z = s tied to the slider node B (0, 0, s);
* proximal link: face z = 0 tied to the node B (0, 0, 0), face z = L2 tied to the node C (0, 0, L2).

Static condensation (Guyan reduction, exact in statics when the interior carries no load):

    K_c = K_bb - K_bi K_ii^-1 K_ib      (6 m x 6 m, N/m, N/rad, N m/rad; m reference nodes)

with b the reference-node DOFs and i every other independent DOF of the constrained system
u = T q (``Constraints.reduce_matrix``). The guideway gives a 6 x 6 tip stiffness (clamped), the link a
12 x 12 free-free stiffness (rank 6). The interior field is recovered as u = X u_ref (``recovery``).
``kind="beam"`` gives the same objects from the 12-DOF beam element (``femcheck.fe.beam``) with the
case's shear option: exactly the analytical cantilever (docs/conventions.md §5).
"""
from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np
import scipy.sparse as sp

log = logging.getLogger(__name__)

PART_KINDS = ("solid", "beam")


@dataclasses.dataclass(frozen=True)
class SuperElement:
    """A part condensed to its reference nodes (local frame of the part, SI).

    K (6m, 6m): condensed stiffness, DOFs (u_x, u_y, u_z, θ_x, θ_y, θ_z) per reference node;
    ref_points (m, 3) m; dofs: unknowns of the FE model before condensation; mesh_s / assembly_s /
    solve_s: wall time of meshing, assembly and factorization + condensation (s); vertices (nv, 3) m and
    tets (nt, 4) of the linear mesh (empty for beams); recovery (3 nv, 6m): vertex displacements
    u = recovery @ u_ref (m); n_tets; solver: linear solver used; cached: read from the result cache.
    """

    name: str
    kind: str
    K: np.ndarray
    ref_points: np.ndarray
    dofs: int
    mesh_s: float
    assembly_s: float
    solve_s: float
    vertices: np.ndarray
    tets: np.ndarray
    recovery: np.ndarray
    solver: str = ""
    cached: bool = False

    @property
    def n_tets(self) -> int:
        return int(len(self.tets))

    def timings(self) -> dict:
        return {"mesh_s": self.mesh_s, "assembly_s": self.assembly_s, "solve_s": self.solve_s}


def condense_solid(part_mesh, E, nu, clamps: tuple[str, ...], couplings: dict[str, np.ndarray],
                   name: str, mesh_s: float = 0.0) -> SuperElement:
    """Condense a solid part (``geometry`` PartMesh) to rigid-coupling reference nodes.

    clamps: region names fixed to zero; couplings: region name -> reference point (3,) m (RBE2, one
    6-DOF node each, in the given order). E (Pa), nu: the part's material.

    The result is cached on disk (:func:`cached_superelement`).
    """
    return cached_superelement(part_mesh.cache_key, E, nu, clamps, couplings, name, lambda: (part_mesh, mesh_s))


def cached_superelement(mesh_key: str, E, nu, clamps, couplings: dict, name: str, build_mesh) -> SuperElement:
    """:func:`condense_solid` through the result cache (:mod:`femcheck.fe.result_cache`): keyed by the mesh's own
    key (its part parameters and the meshing code, known before meshing), the material, the clamps, the couplings
    and the FE code. A second run of the same part reads it without meshing (``mesh_s``, ``assembly_s`` 0,
    ``solve_s`` the read time, ``cached`` True); otherwise ``build_mesh()`` -> (PartMesh, meshing time s) is
    condensed and stored. An empty ``mesh_key`` (a mesh made outside the cache) is never cached."""
    from femcheck.fe import result_cache
    key = None
    if mesh_key:
        key = _superelement_key(mesh_key, E, nu, clamps, couplings, name)
        t0 = time.perf_counter()
        hit = result_cache.load("superelement", key)
        if hit is not None:
            log.info("%s: super-element read from the cache", name)
            return dataclasses.replace(hit, mesh_s=0.0, assembly_s=0.0, solve_s=time.perf_counter() - t0, cached=True)
    part_mesh, mesh_s = build_mesh()
    se = _condense_solid(part_mesh, E, nu, clamps, couplings, name, mesh_s)
    if key is not None:
        result_cache.store("superelement", key, se)
    return se


def _superelement_key(mesh_key: str, E, nu, clamps, couplings: dict, name: str) -> str:
    from femcheck.fe import result_cache
    return result_cache.result_key("superelement", {
        "mesh": mesh_key, "E_Pa": np.asarray(E, float).tolist(), "nu": np.asarray(nu, float).tolist(),
        "clamps": list(clamps), "name": name, "couplings": {k: [float(x) for x in v] for k, v in couplings.items()}})


def _condense_solid(part_mesh, E, nu, clamps, couplings, name, mesh_s) -> SuperElement:
    from femcheck.fe import constraints as cs
    from femcheck.fe.elasticity import assemble_stiffness, dof_triplets, vector_basis
    from femcheck.fe.linear_solver import factorize

    t0 = time.perf_counter()
    mesh = part_mesh.to_skfem()
    basis = vector_basis(mesh, 2)
    K = assemble_stiffness(basis, E, nu)
    ndof, ref = cs.append_reference_nodes(basis.N, len(couplings))
    sets = [cs.clamp(ndof, basis.get_dofs(c).all()) for c in clamps]
    for k, (region, point) in enumerate(couplings.items()):
        pts, trip = dof_triplets(basis, basis.get_dofs(region).all())
        sets.append(cs.rigid_coupling(ndof, ref[k], point, pts, trip))
    con = cs.combine(*sets)
    Kr = con.reduce_matrix(K)
    t1 = time.perf_counter()
    pos = np.full(ndof, -1)
    pos[con.free] = np.arange(con.nfree)
    b = pos[ref.ravel()]
    if np.any(b < 0):
        raise ValueError(f"{name}: a reference-node DOF is constrained; cannot condense onto it")
    inner = np.setdiff1d(np.arange(con.nfree), b)
    Kr = sp.csr_matrix(Kr)
    Kii = Kr[inner][:, inner]
    Kib = Kr[inner][:, b].toarray()
    fac = factorize(Kii, symmetric=True)
    Xi = fac.solve(Kib)
    Kc = Kr[b][:, b].toarray() - Kib.T @ Xi
    Kc = 0.5 * (Kc + Kc.T)
    nv = mesh.p.shape[1]
    Tv = con.T[: 3 * nv]
    recovery = Tv[:, b].toarray() - Tv[:, inner] @ Xi
    t2 = time.perf_counter()
    log.info("%s: %d DOFs, condensed to %d in %.2f s (assembly %.2f s)", name, basis.N, b.size, t2 - t1, t1 - t0)
    return SuperElement(name=name, kind="solid", K=Kc, ref_points=np.array(list(couplings.values()), float),
                        dofs=int(basis.N), mesh_s=mesh_s, assembly_s=t1 - t0, solve_s=t2 - t1,
                        vertices=np.asarray(part_mesh.points), tets=np.asarray(part_mesh.tets),
                        recovery=np.asarray(recovery), solver=fac.method)


def _beam_K(L, material, section, shear: bool):
    from femcheck.fe.beam import local_stiffness
    return local_stiffness(np.array([L]), material.E_Pa, material.G_Pa, section, shear=shear)[0]


def guideway_element(case, length_m: float, kind: str = "solid", size_m: float | None = None) -> SuperElement:
    """Guideway of cantilever length s = ``length_m`` (m), clamped at A: 6 x 6 stiffness at B (0, 0, s)
    in frame A_i (x radial = width b, y tangential = depth h, z = rail)."""
    g = case.guideway
    if kind == "beam":
        from femcheck.fe.beam import BeamSection
        t0 = time.perf_counter()
        sec = BeamSection.rectangle(g.width_radial_m, g.depth_tangential_m, g.material.nu)
        K = _beam_K(length_m, g.material, sec, case.model.beam_shear)[6:, 6:]
        return SuperElement("guideway", "beam", K, np.array([[0, 0, length_m]], float), 12, 0.0, 0.0,
                            time.perf_counter() - t0, np.zeros((0, 3)), np.zeros((0, 4), int), np.zeros((0, 6)))
    if kind != "solid":
        raise ValueError(f"part kind = {kind!r}; expected one of {', '.join(PART_KINDS)}")
    from geometry import guideway
    from geometry.cache import cache_key
    return cached_superelement(cache_key(guideway.PART, guideway.parameters(case, size_m, length_m=length_m)),
                               g.material.E_Pa, g.material.nu, ("lg_clamp",), {"lg_slider": np.array([0.0, 0.0, length_m])},
                               "guideway", lambda: _timed(lambda: guideway.build(case, size_m, length_m=length_m)))


def link_element(case, kind: str = "solid", size_m: float | None = None) -> SuperElement:
    """Proximal link B -> C of length L2: 12 x 12 free-free stiffness at B (0, 0, 0) and C (0, 0, L2) in
    frame B_i (z = link axis; the tube is axisymmetric, so x, y may be any pair normal to z)."""
    pl, L2 = case.proximal_link, case.geometry.proximal_link_length_m
    if kind == "beam":
        from femcheck.fe.beam import BeamSection
        t0 = time.perf_counter()
        sec = BeamSection.tube(pl.outer_diameter_m, pl.inner_diameter_m, pl.material.nu)
        K = _beam_K(L2, pl.material, sec, case.model.beam_shear)
        return SuperElement("proximal_link", "beam", K, np.array([[0, 0, 0], [0, 0, L2]], float), 12, 0.0, 0.0,
                            time.perf_counter() - t0, np.zeros((0, 3)), np.zeros((0, 4), int), np.zeros((0, 12)))
    if kind != "solid":
        raise ValueError(f"part kind = {kind!r}; expected one of {', '.join(PART_KINDS)}")
    from geometry import proximal_link
    from geometry.cache import cache_key
    return cached_superelement(cache_key(proximal_link.PART, proximal_link.parameters(case, size_m)),
                               pl.material.E_Pa, pl.material.nu, (),
                               {"prox_end_B": np.zeros(3), "prox_end_C": np.array([0.0, 0.0, L2])}, "proximal_link",
                               lambda: _timed(lambda: proximal_link.build(case, size_m)))


def superelement_cached(case, part: str, size_m: float, length_m: float | None = None) -> bool:
    """Whether the solid super-element of ``part`` ("guideway" of cantilever ``length_m``, or "link") at mesh size
    ``size_m`` is in the result cache (a read then takes milliseconds: no worker process is worth starting for it)."""
    from femcheck.fe import result_cache
    from geometry import guideway, proximal_link
    from geometry.cache import cache_key
    if part == "guideway":
        g = case.guideway
        mesh_key = cache_key(guideway.PART, guideway.parameters(case, size_m, length_m=length_m))
        return result_cache.has("superelement", _superelement_key(mesh_key, g.material.E_Pa, g.material.nu, ("lg_clamp",),
                                                                  {"lg_slider": np.array([0.0, 0.0, length_m])}, "guideway"))
    pl, L2 = case.proximal_link, case.geometry.proximal_link_length_m
    mesh_key = cache_key(proximal_link.PART, proximal_link.parameters(case, size_m))
    return result_cache.has("superelement", _superelement_key(
        mesh_key, pl.material.E_Pa, pl.material.nu, (), {"prox_end_B": np.zeros(3), "prox_end_C": np.array([0.0, 0.0, L2])},
        "proximal_link"))


def _timed(build):
    """(build(), its wall time s)."""
    t0 = time.perf_counter()
    out = build()
    return out, time.perf_counter() - t0
