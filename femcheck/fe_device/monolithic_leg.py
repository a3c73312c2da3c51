"""Monolithic leg check: one complete leg meshed as ONE contact model, vs the
substructured leg that uses the joints' FE-measured laws.

Monolithic model. Every body of leg i at a test point is meshed with the existing builders and placed in
the link frame B_i with its origin at the ball centre B (z = u_i, x = a1 = unit(z_U × u_i), the frame of
the universal joint, docs/conventions.md §2):

* guideway bar (``geometry.guideway``, frame A_i, length s_i, clamped at A_i), moved by x → R_Bᵀ (R_A x + A − B);
* slider seat + ball (``geometry.spherical_joint``, flat seat of the case), seat normal along u_i;
* link tube (``geometry.proximal_link``, B → C, length L2);
* universal joint (``geometry.universal_joint``: platform yoke arms, cross pins, link yoke arms), at C.

The two joints are meshed exactly as their contact FE meshes them at the same level
(:func:`femcheck.fe_device.joint_fe.level_mesh_options`: the ball graded on the Hertz radius of the leg's
largest force; the pins with warped angles, the level's axial element length and the hub ends as element
levels, so the rigid hub ties exactly ±hub_half_length_m), and each contact pair takes its joint's penalty
factor and exact-surface initial gaps, as in ``build_joint``.

They form one P2 mesh (one global stiffness, materials per body) with three contact pairs (GPTS penalty,
:func:`femcheck.fe.contact.pairing.pair_surfaces`): ball/seat, pin a1/platform bores, pin a2/link bores.
Rigid parts are rigid couplings (RBE2) to reference nodes, exactly as in the substructured parts: the
slider carriage (guideway slider face + seat bottom → node B_g at B), the ball-link clamp (ball cap +
tube end → node B_l at B), the link-yoke clamp (tube end + link-yoke mount → node C_l at C), the cross
hub (→ hub node), the platform (platform-yoke mount → node C_p at C = the platform attachment C_i).
There are no joint springs: the joints are their meshed contact pairs.

The global stiffness is condensed onto the candidate contact DOFs + node C_p with the same exact linear
algebra as the joint FE (PARDISO Schur complement, :func:`femcheck.fe_device.joint_fe._condense`) and the
same contact solver (Newton on the contact energy with exact line search, augmented Lagrangian,
:func:`femcheck.fe_device.joint_fe.solve_joint`). Condensation of linear bodies is exact; it is not a
substructuring with joint laws (the contact iterations act on the contact DOFs of all three joints at
once, coupled through every body of the leg).

Load (seed 000 eq. 1). With ideal passive joints the leg is a two-force member: the released-joint
statics J f = W (:func:`femcheck.fe_device.joint_forces.leg_forces`) give its force f_i at the preload
(5 N at the TCP) and at preload + test (20 N). The check takes the most compressed leg at the point
(largest −f_i over the case's test directions; the ball can only be pushed into its seat) and applies
|f_i| along −u_i at C_p; the platform holds C_p's other five components (as the joint FE holds node b's).
The seat normal is along u_i (the slider seat faces the link at the test point): a flat seat whose normal
is the rail e cannot carry the leg force, the link being 20–45° off the rail (tan 33.5° = 0.66 at P0 is
far above μ = 0.1: the ball would slide off; the joint FE likewise loads the ball along its seat normal).

Substructured leg. The same leg as a series of the guideway super-element (6 × 6 at B, clamped at A),
the link super-element (12 × 12) and the two joints' FE-measured responses
(:func:`femcheck.fe_device.joint_fe.solve_joint` at the same two force levels: node b's displacement along
the joint axis, clearance take-up included). A two-force leg loaded along its axis works each part along
that axis only, so

    δ_sub(F) = F (u_Aᵀ C_lg,tt u_A + c_link,zz) + δ_sp(F) + δ_uj(F)        (m, along −u_i at C_i)

with C_lg = K_lg⁻¹ (frame A, u_A = R_Aᵀ u_i) and c_link,zz the axial compliance of the link clamped at B.
The compared quantity is the displacement of C_i along the leg at both force levels and its eq. 1
increment δ(F20) − δ(F5); ``relative_difference`` is that of the increment.

What this checks (and what it does not). Both models use the same meshes of every body (the joints' too)
and the same contact set-up, so the bodies' own compliances agree by construction. The difference measures what substructuring assumes: that each
joint FE's boundary conditions (seat and platform yoke clamped, node b held in its five other components)
represent the joint inside the leg, where the seat moves with the bending guideway and the ball, link and
cross are free to slide and roll in their frictionless contacts (the mechanisms carry no load).
"""
from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np

from femcheck.errors import FemcheckError

log = logging.getLogger(__name__)

#: agreement asked of the two leg models
AGREEMENT_REL = 0.02
#: force-balance tolerance of the leg's contact solve, ‖r‖ ≤ LEG_RTOL F_20. The joint FE uses 1e-9; the leg's
#: condensed system carries the frictionless mechanisms of the leg (the ball sliding on its seat, the pins
#: sliding along their bores; they carry no load), whose near-zero modes the iteration-matrix spring slows
#: down: at the preload the residual stalls at ≈ 5e-9 F_20 (measured at P0, coarse). The final residual is
#: reported (``residual_rel``).
LEG_RTOL = 1e-7


@dataclasses.dataclass(frozen=True)
class LegLoad:
    """The leg force of one test point (released-joint statics, module doc).

    ``point`` 'P0'..'P8'; ``chain`` leg index; ``direction`` the TCP test direction that compresses it
    most; ``loads_N`` (F5, F20) compressive leg force at the eq. 1 levels (N); ``u`` (3,) link unit vector
    B → C in U; ``inclination_deg`` angle between the link and the rail; geometry of the leg (U, m):
    ``A``, ``B``, ``C`` (3,), ``slider_m`` s_i, ``R_A``, ``R_B`` (3, 3) part frames (columns = axes in U).
    """

    point: str
    chain: int
    direction: str
    loads_N: tuple
    u: np.ndarray
    inclination_deg: float
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    slider_m: float
    R_A: np.ndarray
    R_B: np.ndarray


def leg_load(case, point: str = "P0", chain: int | None = None) -> LegLoad:
    """Force and geometry of the leg the check loads: ``chain`` (default: the most compressed leg at
    ``point`` over the case's test directions). Raises when the chosen leg is not compressed."""
    from femcheck.fe_device.joint_forces import leg_forces
    from geometry.build import leg_at
    from geometry.leg import frames

    f = leg_forces(case, point)  # (n_dir, 2, 6), + = tension
    if chain is None:
        d, chain = np.unravel_index(np.argmin(f[:, 1, :]), (f.shape[0], f.shape[2]))
    else:
        if not 0 <= int(chain) <= 5:
            raise FemcheckError(f"--chain {chain!r}: expected 0..5")
        d = int(np.argmin(f[:, 1, int(chain)]))
    chain = int(chain)
    F5, F20 = -float(f[d, 0, chain]), -float(f[d, 1, chain])
    if F20 <= 0:
        raise FemcheckError(f"leg {chain} at {point} is not compressed by any test direction (a flat seat "
                            f"cannot carry tension)")
    A, B, C, u, e, s = leg_at(case, point, chain)
    R_A, R_B = frames(A, u, e)
    inc = float(np.degrees(np.arccos(np.clip(u @ np.asarray(e, float), -1.0, 1.0))))
    return LegLoad(point.upper(), chain, case.loads.directions[int(d)], (F5, F20), np.asarray(u), inc,
                   np.asarray(A), np.asarray(B), np.asarray(C), float(s), R_A, R_B)


def part_sizes(case, mesh: str) -> dict:
    """Mesh size (m) of each body at a joint-FE mesh level (coarse / default / fine scale every part's
    case default by the same factor, :data:`femcheck.fe_device.joint_fe.MESH_FACTORS`)."""
    from femcheck.fe_device.joint_fe import MESH_FACTORS

    if mesh not in MESH_FACTORS:
        raise FemcheckError(f"--mesh {mesh!r}: expected one of {', '.join(MESH_FACTORS)}")
    f, m = MESH_FACTORS[mesh], case.solid.mesh
    return {"guideway": f * m.guideway_size_m, "proximal_link": f * m.proximal_link_size_m,
            "spherical_joint": f * m.spherical_joint_size_m, "universal_joint": f * m.universal_joint_size_m}


def place_bodies(case, load: LegLoad, sizes: dict, bodies=("guideway", "spherical_joint", "proximal_link",
                                                               "universal_joint"), mesh: str = "coarse") -> list:
    """The leg's part meshes moved into the link frame at B (module doc): list of ``PartMesh``.

    The guideway and the link tube take ``sizes`` (:func:`part_sizes`); the two joints are meshed exactly
    as their contact FE meshes them at level ``mesh`` (:func:`femcheck.fe_device.joint_fe.level_mesh_options`:
    the ball graded on the Hertz radius of the leg's largest force, the pins with warped angles, the axial
    element length and the hub ends as element levels, so the rigid hub ties exactly ±hub_half_length_m)."""
    from femcheck.fe_device.joint_fe import level_mesh_options
    from geometry import guideway, proximal_link, spherical_joint, universal_joint

    L2 = case.geometry.proximal_link_length_m
    out = []
    for name in bodies:
        if name == "guideway":
            pm = guideway.build(case, sizes["guideway"], length_m=load.slider_m)
            out.append(pm.transformed(load.R_B.T @ load.R_A, load.R_B.T @ (load.A - load.B)))
        elif name == "spherical_joint":
            size, opts = level_mesh_options(case, "spherical", mesh, max(load.loads_N))
            out.append(spherical_joint.build(case, size, **opts))
        elif name == "proximal_link":
            out.append(proximal_link.build(case, sizes["proximal_link"]))
        elif name == "universal_joint":
            size, opts = level_mesh_options(case, "universal", mesh, max(load.loads_N))
            out.append(universal_joint.build(case, size, **opts).transformed(np.eye(3), np.array([0, 0, L2])))
        else:
            raise ValueError(f"unknown leg body {name!r}")
    return out


@dataclasses.dataclass(frozen=True)
class LegAssembly:
    """One global P2 model of placed bodies: ``basis`` (skfem), ``K`` (N, N) csr N/m, ``ndof`` with the
    reference nodes, ``refs`` name -> (6,) reference-node DOFs, ``constraints`` (clamps + RBE2 couplings),
    ``mesh`` the skfem mesh (facet regions as boundaries), ``seconds`` assembly wall time."""

    basis: object
    K: object
    ndof: int
    refs: dict
    constraints: object
    mesh: object
    seconds: float


def assemble_leg(case, meshes, clamps, couplings: dict) -> LegAssembly:
    """Merge placed ``meshes`` into one P2 model: stiffness with each body's material, ``clamps`` (region
    names fixed to zero), ``couplings`` node name -> (reference point (3,) m, region names tied to it by
    one rigid coupling)."""
    from femcheck.fe import constraints as cs
    from femcheck.fe.elasticity import assemble_stiffness, dof_triplets, vector_basis
    from geometry.part_mesh import PartMesh, merge

    t0 = time.perf_counter()
    points, tets, body_of_tet, bodies, regions = merge("leg", list(meshes))
    pm = PartMesh("leg", points, tets, body_of_tet, bodies, regions)
    msh = pm.to_skfem()
    basis = vector_basis(msh, 2)
    mats = [case.material(b.material) for b in bodies]
    E = np.array([m.E_Pa for m in mats])[body_of_tet]
    nu = np.array([m.nu for m in mats])[body_of_tet]
    K = assemble_stiffness(basis, E, nu)
    ndof, ref = cs.append_reference_nodes(basis.N, len(couplings))
    refs = {name: np.asarray(ref[k]) for k, name in enumerate(couplings)}
    sets = [cs.clamp(ndof, basis.get_dofs(c).all()) for c in clamps]
    for name, (point, regs) in couplings.items():
        dofs = np.concatenate([basis.get_dofs(r).all() for r in regs])
        pts, trip = dof_triplets(basis, dofs)
        sets.append(cs.rigid_coupling(ndof, refs[name], np.asarray(point, float), pts, trip))
    return LegAssembly(basis, K, ndof, refs, cs.combine(*sets), msh, time.perf_counter() - t0)


def build_monolithic_leg(case, load: LegLoad, mesh: str = "coarse", *, penalty_factor: float | None = None,
                         exact_gaps: bool = True):
    """Mesh, assemble, pair and condense the whole leg (module doc): a
    :class:`femcheck.fe_device.joint_fe.CondensedJoint` named 'leg' whose reference node is C_p.

    Each contact pair is set up as in its joint FE (``build_joint``): the penalty factor of its joint
    (``joint_fe.PENALTY_FACTOR``, or ``penalty_factor`` for all pairs) and, with ``exact_gaps``, the initial
    gaps measured to the exact ball and pin/bore surfaces (the U joint's shifted back to its centre C)."""
    from femcheck.fe.contact.pairing import default_penalty, pair_surfaces
    from femcheck.fe_device import joint_fe as jf

    t0 = time.perf_counter()
    L2 = case.geometry.proximal_link_length_m
    meshes = place_bodies(case, load, part_sizes(case, mesh), mesh=mesh)
    uj_mesh = meshes[-1]
    C = np.array([0.0, 0.0, L2])
    couplings = {
        "C_p": (C, ("uj_platform_mount",)),
        "B_g": (np.zeros(3), ("lg_slider", "sj_seat_mount")),
        "B_l": (np.zeros(3), ("sj_ball_link", "prox_end_B")),
        "C_l": (C, ("prox_end_C", "uj_link_mount")),
        "hub": (np.asarray(uj_mesh.regions["uj_hub"].reference_point, float), ("uj_hub",)),
    }
    asm = assemble_leg(case, meshes, ("lg_clamp",), couplings)
    sj, uj = case.spherical_joint, case.universal_joint
    clearance = float(case.solid.universal_joint.pin_clearance_m)
    spec = [("sj_seat_contact", "sj_ball_contact", sj.seat_material, case.solid.spherical_joint.friction, "spherical"),
            ("uj_a1_bore_contact", "uj_a1_pin_contact", uj.bore_material, case.solid.universal_joint.friction, "universal"),
            ("uj_a2_bore_contact", "uj_a2_pin_contact", uj.bore_material, case.solid.universal_joint.friction, "universal")]
    pairs, h = [], []
    for slave, master, mat, mu, joint in spec:
        factor = jf.PENALTY_FACTOR[joint] if penalty_factor is None else float(penalty_factor)
        sf, mf = asm.mesh.boundaries[slave], asm.mesh.boundaries[master]
        eps = default_penalty(asm.mesh, sf, mat.E_Pa, factor)
        pairs.append(pair_surfaces(asm.basis, sf, mf, penalty_n=eps, friction=mu, name=slave, ndof=asm.ndof))
        h.append(float(np.min(mat.E_Pa * factor / eps)))
    if exact_gaps:  # the ball's before the check (as build_joint), the pins' after it (it measures their chords)
        pairs[0] = jf._exact_sphere_gap(case, pairs[0])
    jf._check_gaps("spherical", pairs[:1], 0.0, h[0])
    jf._check_gaps("universal", pairs[1:], clearance, min(h[1:]))
    if exact_gaps:
        for k in (1, 2):
            at_origin = dataclasses.replace(pairs[k], points=np.asarray(pairs[k].points, float) - C)
            g0 = jf._exact_cylinder_gap(case, at_origin, k - 1).g0
            # the exact cylinders differ from the facets by their chord error only (< c / 2, checked above)
            if np.abs(g0 - pairs[k].g0).max() > 0.5 * clearance + 1e-12:
                raise RuntimeError(f"{pairs[k].name}: exact gaps off the facet gaps by more than the chord error")
            pairs[k] = dataclasses.replace(pairs[k], g0=g0)
    # candidates as in the joint FE: the Hertz patch of the ball; the loaded lines of the pins (the leg in
    # compression pushes the link yoke towards the platform: link bores a2 close on their first-contact
    # line, the cross lifts and the platform bores a1 close on their opposite line, across 2c)
    cand = [jf._hertz_candidates(case, pairs[0], max(load.loads_N)),
            jf._candidates(pairs[1], clearance, "opposite"), jf._candidates(pairs[2], clearance, "first")]
    S, red, ref_r, nfree, nret, nfac, recover = jf._condense(asm.K, asm.constraints, pairs, cand, asm.refs["C_p"])
    return jf.CondensedJoint("leg", S, tuple(red), ref_r, int(asm.basis.N), nfree, nret, time.perf_counter() - t0,
                             clearance, min(h), nfac, int(sum(c.sum() for c in cand)),
                             int(sum(p.n_points for p in pairs)), recover, tuple(pairs))


@dataclasses.dataclass(frozen=True)
class SubstructuredLeg:
    """The series leg (module doc). Compliances along the leg (m/N): ``guideway_m_per_N``
    u_Aᵀ C_lg,tt u_A, ``link_m_per_N``; joint displacements along their axes at (F5, F20) (m):
    ``spherical_m``, ``universal_m`` (FE-measured, clearance take-up included); ``displacement_m`` δ_sub at
    (F5, F20); per joint FE: ``joint_iterations``, ``joint_dofs``; ``seconds`` wall time of the four parts."""

    guideway_m_per_N: float
    link_m_per_N: float
    spherical_m: np.ndarray
    universal_m: np.ndarray
    displacement_m: np.ndarray
    joint_iterations: dict
    joint_dofs: dict
    seconds: float


def substructured_leg(case, load: LegLoad, mesh: str = "coarse") -> SubstructuredLeg:
    """Guideway and link super-elements (same meshes as the monolithic model) in series with the two
    joints' contact FE (:func:`femcheck.fe_device.joint_fe.solve_joint`) at the leg's force levels."""
    from femcheck.fe_device import joint_fe as jf
    from femcheck.fe_device.parts import guideway_element, link_element

    t0 = time.perf_counter()
    sizes = part_sizes(case, mesh)
    lg = guideway_element(case, load.slider_m, "solid", sizes["guideway"])
    uA = load.R_A.T @ load.u
    c_lg = float(uA @ np.linalg.inv(lg.K)[:3, :3] @ uA)
    link = link_element(case, "solid", sizes["proximal_link"])
    c_link = float(np.linalg.inv(link.K[6:, 6:])[2, 2])
    disp, its, dofs = {}, {}, {}
    for joint, sign in (("spherical", -1.0), ("universal", 1.0)):
        model = jf.build_joint(case, joint, mesh, max_load_N=max(load.loads_N))
        r = jf.solve_joint(model, load.loads_N, sign, penetration_tol=_penetration_tol(case, load.loads_N, (joint,)))
        disp[joint], its[joint], dofs[joint] = np.asarray(r.axial_m), r.iterations, r.dofs
    F = np.asarray(load.loads_N)
    total = F * (c_lg + c_link) + disp["spherical"] + disp["universal"]
    return SubstructuredLeg(c_lg, c_link, disp["spherical"], disp["universal"], total, its, dofs,
                            time.perf_counter() - t0)


def _penetration_tol(case, loads, joints=("spherical", "universal")) -> float:
    """1e-3 of the smallest analytical joint approach at the preload (as ``check-joints``), m."""
    from femcheck.fe_device import joint_fe as jf

    return min(1e-3 * float(jf.analytical_compliance(case, j, loads)[2, 2]) * min(loads) for j in joints)


@dataclasses.dataclass(frozen=True)
class MonolithicLegResult:
    """Monolithic vs substructured leg at one test point (SI; module doc).

    ``displacement_monolithic_m`` / ``displacement_substructured_m`` (2,): C_i along the leg force at
    (F5, F20); ``increment_*_m`` their eq. 1 increments; ``relative_difference`` of the increments
    (monolithic − substructured) / substructured, ``relative_difference_total`` of the F20 values;
    monolithic solve: ``dofs`` (P2 mesh), ``free_dofs``, ``retained`` (condensed), ``contact_points``,
    ``candidate_points``, ``closed_points``, ``iterations``, ``factorizations``, ``augmentations``,
    (``joint_*``: the same comparison for the joints' share of the increment alone);
    ``line_search_cuts``, ``stabilization_force_share``, ``residual_rel``, ``condense_s``, ``seconds``.
    """

    load: LegLoad
    mesh: str
    displacement_monolithic_m: np.ndarray
    displacement_substructured_m: np.ndarray
    dofs: int
    free_dofs: int
    retained: int
    contact_points: int
    candidate_points: int
    closed_points: int
    iterations: int
    factorizations: int
    augmentations: int
    line_search_cuts: int
    stabilization_force_share: float
    residual_rel: float
    condense_s: float
    seconds: float
    substructured: SubstructuredLeg

    @property
    def increment_monolithic_m(self) -> float:
        return float(self.displacement_monolithic_m[-1] - self.displacement_monolithic_m[0])

    @property
    def increment_substructured_m(self) -> float:
        return float(self.displacement_substructured_m[-1] - self.displacement_substructured_m[0])

    @property
    def relative_difference(self) -> float:
        return (self.increment_monolithic_m - self.increment_substructured_m) / self.increment_substructured_m

    @property
    def joint_increment_monolithic_m(self) -> float:
        """The joints' share of the monolithic increment: minus the super-elements' F (c_lg + c_link), m."""
        s, F = self.substructured, self.load.loads_N
        return self.increment_monolithic_m - (F[1] - F[0]) * (s.guideway_m_per_N + s.link_m_per_N)

    @property
    def joint_increment_substructured_m(self) -> float:
        """δ_sp + δ_uj increment of the two joint contact FE solves, m."""
        s = self.substructured
        return float(s.spherical_m[-1] - s.spherical_m[0] + s.universal_m[-1] - s.universal_m[0])

    @property
    def joint_relative_difference(self) -> float:
        """Relative difference of the joints' share alone (the bodies' own compliances agree by construction:
        same meshes): what the substructuring of the joints changes."""
        return (self.joint_increment_monolithic_m - self.joint_increment_substructured_m) / self.joint_increment_substructured_m

    @property
    def relative_difference_total(self) -> float:
        m, s = self.displacement_monolithic_m[-1], self.displacement_substructured_m[-1]
        return float((m - s) / s)

    def to_json(self) -> dict:
        """Flat JSON object (SI, names with units)."""
        s = self.substructured
        return {"point": self.load.point, "chain": self.load.chain, "direction": self.load.direction,
                "mesh": self.mesh, "loads_N": list(self.load.loads_N), "inclination_deg": self.load.inclination_deg,
                "dofs": self.dofs, "free_dofs": self.free_dofs, "retained_dofs": self.retained,
                "contact_points": self.contact_points, "candidate_points": self.candidate_points,
                "closed_points": self.closed_points, "iterations": self.iterations,
                "factorizations": self.factorizations, "augmentations": self.augmentations,
                "line_search_cuts": self.line_search_cuts, "stabilization_force_share": self.stabilization_force_share,
                "residual_rel": self.residual_rel, "condense_s": self.condense_s, "seconds": self.seconds,
                "displacement_monolithic_m": self.displacement_monolithic_m.tolist(),
                "displacement_substructured_m": self.displacement_substructured_m.tolist(),
                "increment_monolithic_m": self.increment_monolithic_m,
                "increment_substructured_m": self.increment_substructured_m,
                "relative_difference": self.relative_difference,
                "relative_difference_total": self.relative_difference_total,
                "joint_increment_monolithic_m": self.joint_increment_monolithic_m,
                "joint_increment_substructured_m": self.joint_increment_substructured_m,
                "joint_relative_difference": self.joint_relative_difference,
                "substructured_guideway_m_per_N": s.guideway_m_per_N, "substructured_link_m_per_N": s.link_m_per_N,
                "substructured_spherical_m": s.spherical_m.tolist(), "substructured_universal_m": s.universal_m.tolist(),
                "substructured_joint_iterations": s.joint_iterations, "substructured_joint_dofs": s.joint_dofs,
                "substructured_seconds": s.seconds}


def check_monolithic_leg(case, point: str = "P0", mesh: str = "coarse", chain: int | None = None) -> MonolithicLegResult:
    """Monolithic leg contact FE vs the substructured leg at ``point`` (module doc). A contact solve that
    does not converge raises :class:`femcheck.errors.ConvergenceError` (residual history, chattering points)."""
    from femcheck.fe_device import joint_fe as jf

    load = leg_load(case, point, chain)
    t0 = time.perf_counter()
    model = build_monolithic_leg(case, load, mesh)
    # the platform pushes C_p along −u (−z of the link frame); its other five components are held
    r = jf.solve_joint(model, load.loads_N, -1.0, penetration_tol=_penetration_tol(case, load.loads_N), rtol=LEG_RTOL)
    seconds = time.perf_counter() - t0
    log.info("monolithic leg %s chain %d: %d DOFs, %d retained, %d iterations, %.1f s", load.point, load.chain,
             model.dofs, model.retained, r.iterations, seconds)
    size = (model.dofs, model.free_dofs, model.retained, model.contact_points, model.candidate_points)
    factorizations, condense_s = r.factorizations + model.factorizations, model.condense_s
    del model  # its body factorizations (the interior recovery): free them before the joint FE solves
    sub = substructured_leg(case, load, mesh)
    return MonolithicLegResult(load, mesh, np.asarray(r.axial_m), sub.displacement_m, *size, r.closed_points,
                               r.iterations, factorizations, r.augmentations, r.line_search_cuts,
                               r.stabilization_force_share, r.residual_rel, condense_s, seconds, sub)
