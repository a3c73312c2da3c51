"""Passive joints as meshed contact bodies, condensed onto their contact surfaces.

Each joint is meshed with P2 tetrahedra (``geometry.spherical_joint``: ball in a flat or socket seat;
``geometry.universal_joint``: cross pins in yoke bores, with the case's clearance and pin position),
materials per body from the case, GPTS penalty contact with Coulomb friction, augmented Lagrangian and
Newton–Raphson with factorization reuse on the condensed system
(:func:`femcheck.fe.contact.condensed_solver.solve_condensed_contact`, seed 004 §3.3).

Reference nodes. Body a is held (spherical: the seat bottom on the slider; universal: the top faces of
the platform-yoke arms); body b is tied by a rigid coupling (RBE2) to the reference node b
(spherical: the ball cap to the link, node B at the ball centre; universal: the link-yoke arm bottoms,
node at their centre). The joint's 6 x 6 compliance is the one of node b relative to the held body a,
in the joint frame (spherical: z = seat normal; universal: frame B_i, z = link axis, x = a1, y = a2).

Static condensation (why it converges). The monolithic solve carries every interior DOF through every
contact iteration. Here the constrained stiffness K_q = Tᵀ K T is split into the DOFs the contact
operators touch plus the reference node (set r) and the rest (set i); K_ii is factorized once and the
Schur complement

    S = K_rr − K_ri K_ii⁻¹ K_ir                               (exact for the linear bodies)

comes from PARDISO's partial factorization, or (no MKL) from multi-right-hand-side back-substitutions
with one factorization per body (K_ii is block diagonal: the bodies meet only at retained contact DOFs);
the same factorization recovers the interior after the contact solve
(:func:`femcheck.fe.schur_complement.condense`). The contact iterations (status changes,
Uzawa updates, refactorizations) then run on the small dense S only, as Newton on the convex contact
energy with an exact line search (no active-set chattering; a cross floating in its 2c clearance is
seated in one step). The initial active set is the one the Hertz patch predicts: every candidate point
whose initial gap is within ``closure`` (twice the clearance plus a margin) starts closed; the load is
stepped (the eq. 1 levels).

Mesh levels (:func:`femcheck.fe_device.mesh_levels.joint_mesh_sizes`). Ball in seat: graded on the
Hertz radius a at the largest joint load: element edge a / 3, a / 4.5, a / 6 (coarse, default, fine) on
a contact disc of radius 1.3 a, growing by 0.5 per unit distance from it (bisection of the structured
ball and seat), the bulk at the case's size at every level. The initial gaps are measured to the exact
ball surface (:func:`_exact_sphere_gap`: the straight facets' sagitta would open two thirds of the
patch's Gauss points), the contact iterations start from the Hertz patch of the preload, and the stick
tangent sticks the contact area (closed points and the points whose final gap is below 1e-3 of the
approach increment). Changed active sets are solved by Woodbury updates of the last dense Cholesky
(``low_rank_updates``). Universal joint: the nodes around pins and bores crowded at the loaded top/bottom
lines by an angular warp (spacing 0.5, 0.25, 0.125 of the uniform one there) and the element length along
the pins and through the yoke arms 2, 1.4, 1 x the case's size (the bulk), the hub ends element levels (the
rigid hub ties exactly hub_half_length_m), in-plane bulk twice the case's size; initial gaps between the
exact cylinders (:func:`_exact_cylinder_gap`).

Compliances (SI: m/N, rad/(N m), m/(N m)):
* secant along the joint axis for the eq. 1 increment: (u(F_20) − u(F_5)) / (F_20 − F_5);
* tangent 6 x 6 at the test state: the condensed iteration matrix with the converged contact status
  (closed points: ε_n, sticking points: ε_t), reduced to node b; components the contact cannot carry
  (a frictionless or fully sliding rotation) come out as ``inf``.
"""
from __future__ import annotations

import dataclasses
import logging
import math
import time

import numpy as np
import scipy.sparse as sp

from femcheck.errors import ConvergenceError, FemcheckError

log = logging.getLogger(__name__)

JOINTS = ("spherical", "universal")
MESH_FACTORS = {"coarse": 2.0, "default": 1.0, "fine": 0.5}
COMPONENTS = ("u_x", "u_y", "u_z", "theta_x", "theta_y", "theta_z")


class JointGeometryError(FemcheckError):
    """Initial interpenetration beyond the clearance, or a clearance the mesh cannot resolve."""


class CandidateBandError(ConvergenceError):
    """The solved contact reaches a point outside the candidate band (a pin bending into its bore away from the
    loaded lines): the solve is not valid for this band; a wider one (:data:`CANDIDATE_BANDS`) may be."""


@dataclasses.dataclass(frozen=True)
class CondensedJoint:
    """Joint FE condensed onto its contact DOFs and reference node.

    ``S`` (n_r, n_r) dense N/m Schur complement; ``pairs`` contact pairs with operators on the n_r
    retained DOFs; ``ref`` (6,) indices of node b in the retained set; ``dofs`` mesh DOFs (P2, 3 per
    node); ``free_dofs`` after constraints; ``retained`` n_r; ``condense_s`` wall time; ``gap0_min``,
    ``clearance_m``, ``contact_h_m`` (m) for the geometry checks; ``factorizations`` of K_ii (1);
    ``candidate_points`` of ``contact_points`` kept in the contact iterations (:func:`_candidates`);
    ``recover`` the callable that returns the gaps of *all* contact points from a condensed displacement.
    """

    joint: str
    S: np.ndarray
    pairs: tuple
    ref: np.ndarray
    dofs: int
    free_dofs: int
    retained: int
    condense_s: float
    clearance_m: float
    contact_h_m: float
    factorizations: int
    candidate_points: int
    contact_points: int
    recover: object = dataclasses.field(repr=False, compare=False, default=None)
    full_pairs: tuple = dataclasses.field(repr=False, compare=False, default=())


def _materials(pm, mats: dict):
    names = [b.name for b in pm.bodies]
    key = [next(k for k in mats if k in names[b]) for b in pm.body_of_tet]
    E = np.array([mats[k].E_Pa for k in key])
    nu = np.array([mats[k].nu for k in key])
    return E, nu


def _mesh_size(case, joint: str, mesh: str) -> float:
    if mesh not in MESH_FACTORS:
        raise FemcheckError(f"--mesh {mesh!r}: expected one of {', '.join(MESH_FACTORS)}")
    m = case.solid.mesh
    base = m.spherical_joint_size_m if joint == "spherical" else m.universal_joint_size_m
    return MESH_FACTORS[mesh] * base


def level_mesh_options(case, joint: str, mesh: str = "coarse", max_load_N: float | None = None) -> tuple:
    """The joint's mesh at a level, as ``build_joint`` meshes it: (bulk size (m), keyword options of
    ``geometry.spherical_joint.build`` / ``geometry.universal_joint.build``) from
    :func:`femcheck.fe_device.mesh_levels.joint_mesh_sizes` (the ball: contact edge a / k on a disc of 1.3 a;
    the pins: warped angles, axial element length, radial contact edge, hub ends as element levels). The
    monolithic leg (:mod:`femcheck.fe_device.monolithic_leg`) meshes its joints with the same options."""
    from femcheck.fe_device.mesh_levels import joint_mesh_sizes

    if joint not in JOINTS:
        raise FemcheckError(f"--joint {joint!r}: expected one of {', '.join(JOINTS)} or all")
    _mesh_size(case, joint, mesh)  # the level's named error
    ms = joint_mesh_sizes(case, joint, mesh, max_load_N)
    if joint == "spherical":
        return ms.bulk_m, {"contact_size_m": ms.contact_m, "contact_zone_radius_m": ms.zone_m, "grading": ms.grading}
    return ms.bulk_m, ({"contact_warp": ms.contact_warp, "contact_size_m": ms.surface_m, "axial_size_m": ms.axial_m,
                        "hub_levels": ms.hub_levels} if ms.contact_warp else {})


#: penalty factor ε = factor E / h per joint: the ball in seat is stiffer (fewer Uzawa updates, the stick
#: tangent within 1 % of the tied limit at a/4); the pins keep the value they were measured with
PENALTY_FACTOR = {"spherical": 1000.0, "universal": 100.0}


def _joint_mesh(case, joint: str, mesh: str, max_load_N, mesh_options):
    """The meshed joint and its contact set-up: (pm, mats, mu, held, coupled, pairs_spec, clearance) with
    ``mu`` the case's friction (build_joint overrides it when asked)."""
    size = _mesh_size(case, joint, mesh)
    if joint == "spherical":
        from geometry import spherical_joint
        sj = case.spherical_joint
        if mesh_options is None:  # the graded level: contact edge a / k on a disc of 1.3 a, bulk unchanged
            size, mesh_options = level_mesh_options(case, joint, mesh, max_load_N)
        pm = spherical_joint.build(case, size, **mesh_options)
        mats = {"ball": sj.ball_material, "seat": sj.seat_material}
        mu = case.solid.spherical_joint.friction
        held, coupled, pairs_spec = "sj_seat_mount", "sj_ball_link", [("sj_seat_contact", "sj_ball_contact", sj.seat_material)]
        clearance = 0.0
    else:
        from geometry import universal_joint
        uj = case.universal_joint
        if mesh_options is None:
            size, mesh_options = level_mesh_options(case, joint, mesh, max_load_N)
        pm = universal_joint.build(case, size, **mesh_options)
        mats = {"pin": uj.pin_material, "yoke": uj.bore_material}
        mu = case.solid.universal_joint.friction
        held, coupled = "uj_platform_mount", "uj_link_mount"
        pairs_spec = [(f"uj_a{k}_bore_contact", f"uj_a{k}_pin_contact", uj.bore_material) for k in (1, 2)]
        clearance = float(case.solid.universal_joint.pin_clearance_m)
    return pm, mats, mu, held, coupled, pairs_spec, clearance


def build_joint(case, joint: str, mesh: str = "coarse", *, penalty_factor: float | None = None,
                friction: float | None = None, max_load_N: float | None = None,
                mesh_options: dict | None = None, exact_gaps: bool = True, band: int = 0) -> CondensedJoint:
    """Mesh, assemble, constrain and condense one joint (module doc). ``friction`` defaults to the case's μ.
    ``band``: index into :data:`CANDIDATE_BANDS` of the pin-in-bore candidate band (0: the loaded lines only).

    ``max_load_N``: the largest load the joint will carry; the ball-in-seat candidates are then the
    points of the Hertz patch and a margin (:func:`_hertz_candidates`) instead of the whole meshed contact
    region (4x fewer retained DOFs at the default mesh); ``None`` keeps every point."""
    from femcheck.fe import constraints as cs
    from femcheck.fe.contact.pairing import default_penalty, pair_surfaces
    from femcheck.fe.elasticity import assemble_stiffness, dof_triplets, vector_basis

    if joint not in JOINTS:
        raise FemcheckError(f"--joint {joint!r}: expected one of {', '.join(JOINTS)} or all")
    penalty_factor = PENALTY_FACTOR[joint] if penalty_factor is None else float(penalty_factor)
    t0 = time.perf_counter()
    pm, mats, mu, held, coupled, pairs_spec, clearance = _joint_mesh(case, joint, mesh, max_load_N, mesh_options)
    mu = mu if friction is None else friction
    msh = pm.to_skfem()
    basis = vector_basis(msh, 2)
    E, nu = _materials(pm, mats)
    K = assemble_stiffness(basis, E, nu)
    # a revolute's pin in its bores (``hub_held``): the cross's hub is held (the pin sits in the other body's eye), so
    # the load runs from the link yoke through the one pin a2 and its bores; the platform-yoke pin carries nothing
    hub_held = joint == "universal" and bool(getattr(case, "hub_held", False))
    nref = 2 if joint == "universal" and not hub_held else 1
    ndof, refs = cs.append_reference_nodes(basis.N, nref)
    ref_b = np.asarray(refs[0])
    ref_point_b = np.asarray(pm.regions[coupled].reference_point, float) if hasattr(pm, "regions") else np.zeros(3)
    pts, trip = dof_triplets(basis, basis.get_dofs(coupled).all())
    parts = [cs.clamp(ndof, basis.get_dofs(held).all()), cs.rigid_coupling(ndof, ref_b, ref_point_b, pts, trip)]
    if hub_held:
        parts.append(cs.clamp(ndof, basis.get_dofs("uj_hub").all()))
    elif joint == "universal":
        hp, ht = dof_triplets(basis, basis.get_dofs("uj_hub").all())
        hub_point = np.asarray(pm.regions["uj_hub"].reference_point, float)
        parts.append(cs.rigid_coupling(ndof, np.asarray(refs[1]), hub_point, hp, ht))
    C = cs.combine(*parts)
    pairs, h_c = [], np.inf
    for slave, master, mat in pairs_spec:
        sf, mf = msh.boundaries[slave], msh.boundaries[master]
        eps = default_penalty(msh, sf, mat.E_Pa, penalty_factor)
        pr = pair_surfaces(basis, sf, mf, penalty_n=eps, friction=mu, name=slave, ndof=ndof)
        pairs.append(pr)
        h_c = min(h_c, float(np.min(mat.E_Pa * penalty_factor / eps)))
    if joint == "spherical":
        pairs = [_exact_sphere_gap(case, p) for p in pairs]
    _check_gaps(joint, pairs, clearance, h_c)
    if joint == "universal" and exact_gaps:  # after the check: the facet-chord error is what it measures
        pairs = [_exact_cylinder_gap(case, p, k) for p, k in zip(pairs, (0, 1))]
    # universal joint pushed along +z by the link: the link bore (a2) closes on its first-contact line,
    # the cross lifts and the platform bore (a1) closes on its opposite line (across 2c)
    lines = ("opposite", "first") if joint == "universal" else ("both",)
    widen, angle = CANDIDATE_BANDS[band]
    lines = ("both",) * len(lines) if widen else lines
    cand = [_candidates(p, clearance, ln, angle) for p, ln in zip(pairs, lines)]
    if joint == "spherical" and max_load_N is not None:
        cand = [c & _hertz_candidates(case, p, max_load_N) for c, p in zip(cand, pairs)]
    S, red_pairs, ref_r, nfree, nret, nfac, recover = _condense(K, C, pairs, cand, ref_b)
    return CondensedJoint(joint, S, tuple(red_pairs), ref_r, int(basis.N), nfree, nret, time.perf_counter() - t0,
                          clearance, h_c, nfac, int(sum(c.sum() for c in cand)), int(sum(p.n_points for p in pairs)),
                          recover, tuple(pairs))


def _exact_sphere_gap(case, pair):
    """The pair with its initial gaps measured to the exact ball (and cup) surface instead of the straight
    facets: g0 = |x_s| − R_b at each slave point x_s (ball centre at the origin), x_s projected onto the
    socket's cup sphere first where the seat is a socket (the flat seat is exact).

    Why: the mesh geometry is linear (P1 facets, P2 displacements), so a facet of edge e on the ball is off
    the sphere by up to its sagitta e² / (8 R_b) (0.35 µm at e = a/4). Measured to the facets, the gaps in
    the Hertz patch ripple by that much and GPTS closes only the Gauss points near the facet corners (a
    third of the patch at a/4, the rest open by up to 0.26 µm): the stick state then sticks a subset that
    changes with the mesh. The displacement operators are unchanged (P2 on the facets)."""
    so = case.solid.spherical_joint
    R = float(case.spherical_joint.ball_radius_m)
    x = np.asarray(pair.points, float)
    if so.seat == "socket":
        cc = np.array([0.0, 0.0, float(so.socket_clearance_m)])
        rs = R + float(so.socket_clearance_m)
        d = x - cc
        x = cc + rs * d / np.linalg.norm(d, axis=1)[:, None]
    return dataclasses.replace(pair, g0=np.linalg.norm(x, axis=1) - R)


def _exact_cylinder_gap(case, pair, axis: int):
    """The pin-in-bore pair with its initial gaps measured between the exact bore and pin cylinders:
    each slave (bore) point is projected onto the bore circle of radius r + c about the yoke axis (the
    ``axis`` coordinate, 0: a1 = x, 1: a2 = y), and g0 = its distance from the pin axis (lowered by c
    with ``pin_position = "bottom"``) − r. The straight facets' chord error (≈ 1.4 µm at the coarse mesh,
    a seventh of the 10 µm clearance that the conformal contact depends on) then no longer enters the gaps."""
    uj, so = case.universal_joint, case.solid.universal_joint
    r, c = float(uj.pin_radius_m), float(so.pin_clearance_m)
    delta = c if so.pin_position == "bottom" else 0.0
    others = [k for k in range(3) if k != axis]
    q = np.asarray(pair.points, float)[:, others]
    q = (r + c) * q / np.linalg.norm(q, axis=1)[:, None]
    return dataclasses.replace(pair, g0=np.linalg.norm(q - np.array([0.0, -delta]), axis=1) - r)


def _check_gaps(joint: str, pairs, clearance: float, h_c: float) -> None:
    """Named errors: initial interpenetration beyond the clearance, and a clearance the mesh cannot resolve.

    Nodes lie exactly on the pin, bore and ball surfaces, so an initial gap g0 < 0 is the chord error of
    the straight-sided facets (sagitta ≈ h²/(8 r)). Beyond the clearance (or beyond 0.1 % of the contact
    edge where there is none) the bodies start interpenetrating; for a pin in its bore, a chord error
    above half the clearance means the clearance is not resolved (the gap field is mostly facet noise).
    """
    g0 = np.concatenate([p.g0 for p in pairs])
    pen = float(max(-g0.min(), 0.0))
    if pen > max(clearance, 1e-3 * h_c):
        raise JointGeometryError(f"{joint} joint: initial interpenetration {pen:.3g} m exceeds the clearance "
                                 f"{clearance:.3g} m (check the case's [{joint}_joint] / [solid.{joint}_joint] dimensions)")
    if joint == "universal" and clearance > 0 and pen > 0.5 * clearance:
        raise JointGeometryError(f"universal joint: pin clearance {clearance:.3g} m is not resolved by the contact mesh "
                                 f"(facet-chord error {pen:.3g} m > half the clearance); use a finer --mesh or raise "
                                 f"[solid.universal_joint] pin_clearance_m")


#: candidate band of a pin in its bore: points within this angle of the bore's bottom or top line
CANDIDATE_ANGLE_RAD = 0.35
#: the candidate bands tried in turn when the contact leaves the previous one (:func:`femcheck.fe_device.joint_models.solve_widening`):
#: (both lines of every bore, angle rad). First the loaded lines (the Hertz prediction); then both lines of each
#: bore (a thin pin bends under the load: its ends lift off the loaded line and bear on the opposite one near the
#: bore's mouth); then both lines at twice the angle (the bending rolls the contact further round the bore)
CANDIDATE_BANDS = ((False, CANDIDATE_ANGLE_RAD), (True, CANDIDATE_ANGLE_RAD), (True, 2.0 * CANDIDATE_ANGLE_RAD))


def _candidates(pair, clearance: float, lines: str = "both", angle_rad: float = CANDIDATE_ANGLE_RAD) -> np.ndarray:
    """Contact points kept in the iterations: the Hertz-predicted contact zones and a margin.

    Ball in seat: every point of the contact region (it is already the Hertz zone plus margin). Pin in
    bore with clearance c: the gap is c (1 − cos θ) from the line of first contact (θ = 0) and 2c − that
    on the opposite line, the one a load reversal closes; the Hertz half-width of the conformal line
    contact at 20 N is a few degrees, so points within ``CANDIDATE_ANGLE_RAD`` (20°) of either line are
    kept, the angle taken between the master normal and the first-contact normal (the gaps carry the
    facet-chord error; without normals, the band falls back to the gaps). ``lines`` ('first' | 'opposite' | 'both') selects the line(s) the load direction closes (the
    universal joint pushed along +z closes the link bore on its first-contact line and the platform bore
    on its opposite line, across 2c). The kept set is verified after the solve: every dropped point must
    still be open.
    """
    if clearance <= 0:
        return np.ones(pair.n_points, bool)
    normal = getattr(pair, "normal", None)
    if normal is not None:
        # by angle: the gaps carry the facet-chord error (≈ 1.4 µm at the coarse mesh, above the 0.6 µm
        # that 20° means for c = 10 µm), so a band on g0 drops contact points; the master normals do not
        near = pair.g0 <= pair.g0.min() + 0.1 * clearance
        n0 = normal[near].mean(axis=0)
        cos = normal @ (n0 / np.linalg.norm(n0))
        first, opposite = cos >= math.cos(angle_rad), cos <= -math.cos(angle_rad)
        return {"first": first, "opposite": opposite, "both": first | opposite}[lines]
    band = clearance * (1.0 - math.cos(angle_rad))
    first, opposite = pair.g0 <= band, pair.g0 >= 2.0 * clearance - band
    return {"first": first, "opposite": opposite, "both": first | opposite}[lines]


#: ball in seat: candidate points have an initial gap below this many Hertz approaches at the largest
#: load (the gap grows as r² / (2 R*) and the patch edge a has g0 = δ_H / 2, so 0.85 δ_H keeps
#: r ≤ 1.3 a, the fine contact disc of the graded levels; the FE patch ends at 0.99 a, and the band is
#: verified after the solve)
HERTZ_BAND = 0.85


def _hertz_candidates(case, pair, F_max: float) -> np.ndarray:
    """Ball-in-seat points within the Hertz band (``HERTZ_BAND``) of the largest load, plus the facet-chord
    error of the contact mesh (the gaps carry it). Verified after the solve: every dropped point stays open."""
    from femcheck.fe_device.contact_scales import device_springs

    d = float(device_springs(case).ball_approach(F_max))
    chord = max(-float(pair.g0.min()), 0.0)
    return pair.g0 <= HERTZ_BAND * d + 2.0 * chord


def _prune(B) -> sp.csr_matrix:
    """Drop the round-off entries of a contact operator: P2 shape functions of the nodes off a facet
    vanish on it, so only the facet's 6 nodes (per side) carry weight (fewer retained DOFs)."""
    B = sp.csr_matrix(B)
    B.data[np.abs(B.data) < 1e-12 * np.abs(B.data).max()] = 0.0
    B.eliminate_zeros()
    return B


def _condense(K, C, pairs, cand, ref_b):
    """Schur complement of Tᵀ K T onto the candidate-contact DOFs and node b (module doc;
    :func:`femcheck.fe.schur_complement.schur_complement`: PARDISO's own, else CHOLMOD's per body)."""
    from femcheck.fe.constraints import pad
    from femcheck.fe.schur_complement import condense

    T = C.T
    K = pad(sp.csr_matrix(K), C.ndof)
    Kq = sp.csr_matrix(T.T @ (K @ T))
    Bn_all = [_prune(p.B_n @ T) for p in pairs]
    Bt_all = [_prune(p.B_t @ T) for p in pairs]
    Bn = [b[c] for b, c in zip(Bn_all, cand)]
    Bt = [b[np.flatnonzero(np.repeat(c, 2))] for b, c in zip(Bt_all, cand)]
    # node b's reduced DOFs: the columns of T that move node b, ordered as u_x, u_y, u_z, θ_x, θ_y, θ_z
    Tb = sp.csr_matrix(T[ref_b])
    ref_q = np.unique(Tb.indices)
    if ref_q.size != 6:
        raise FemcheckError(f"reference node maps to {ref_q.size} reduced DOFs, expected 6")
    ref_q = ref_q[np.argsort(np.argmax(np.abs(Tb[:, ref_q].toarray()), axis=0))]
    touched = np.unique(np.concatenate([b.indices for b in Bn + Bt] + [ref_q]))
    n = Kq.shape[0]
    mask = np.zeros(n, bool)
    mask[touched] = True
    r = np.flatnonzero(mask)
    # one factorization (PARDISO's partial one, or one per body) for S and for the recovery of the interior
    cond = condense(Kq, r)
    S = cond.S
    pos = np.full(n, -1)
    pos[r] = np.arange(r.size)
    red = [dataclasses.replace(p, B_n=sp.csr_matrix(bn[:, r]), B_t=sp.csr_matrix(bt[:, r]),
                               g0=p.g0[c], weights=p.weights[c], points=p.points[c], normal=p.normal[c],
                               t1=p.t1[c], t2=p.t2[c], penalty_n=p.penalty_n[c], penalty_t=p.penalty_t[c],
                               slave_facet=p.slave_facet[c], master_facet=p.master_facet[c],
                               projection_distance=p.projection_distance[c])
           for p, bn, bt, c in zip(pairs, Bn, Bt, cand)]

    def recover(u_r):
        """Gaps (m) of all contact points of every pair for a condensed displacement u_r (n_r,)."""
        q = cond.extend(u_r)
        return [p.g0 + b @ q for p, b in zip(pairs, Bn_all)]

    return S, red, pos[ref_q], int(n), int(r.size), cond.factorizations, recover


@dataclasses.dataclass(frozen=True)
class JointResponse:
    """Contact-FE response of one joint at one load state (SI, joint frame; module doc).

    ``loads_N`` the force levels along the joint axis (eq. 1: preload, test); ``axial_m`` (n,) node-b
    displacement along the load; ``secant_axial_m_per_N``; ``tangent`` (6, 6) stick compliance at the test
    load; ``closed_points`` contact points closed at the test load; ``iterations``, ``factorizations``,
    ``augmentations`` of the contact solve; ``dofs``, ``free_dofs``, ``retained``; ``seconds`` (total),
    ``condense_s``; ``line_search_cuts`` (iterations with a step < 1), ``stabilized_iterations`` and
    ``stabilization_force_share`` (the iteration-matrix spring, :mod:`femcheck.fe.contact.condensed_solver`),
    ``residual_rel`` final ‖r‖ / F_20.
    """

    joint: str
    loads_N: tuple
    axial_m: np.ndarray
    secant_axial_m_per_N: float
    tangent: np.ndarray
    tangent_stiffness: np.ndarray
    closed_points: int
    iterations: int
    factorizations: int
    augmentations: int
    dofs: int
    free_dofs: int
    retained: int
    seconds: float
    condense_s: float
    line_search_cuts: int = 0
    stabilized_iterations: int = 0
    stabilization_force_share: float = 0.0
    residual_rel: float = 0.0
    #: (n, 6, 6) stick tangent stiffness at every load level (``solve_joint(..., level_tangents=True)``), else None
    level_tangent_stiffness: np.ndarray | None = None
    low_rank_updates: int = 0

    @property
    def fe_compliance(self) -> np.ndarray:
        """6 x 6: the tangent with its axial entry replaced by the eq. 1 secant (the compared state)."""
        C = self.tangent.copy()
        C[2, 2] = self.secant_axial_m_per_N
        return C

    @property
    def component_compliance(self) -> np.ndarray:
        """(6,) compliance of each component with the other five held, 1 / K_kk of the tangent stiffness,
        axial = the eq. 1 secant: what a per-component joint spring of the analytical model describes
        (a free ball rolls about its contact point under a lateral force at B; the link prevents that)."""
        with np.errstate(divide="ignore"):
            c = np.where(np.diag(self.tangent_stiffness) > 0, 1.0 / np.diag(self.tangent_stiffness), np.inf)
        c[2] = self.secant_axial_m_per_N
        return c


def solve_joint(model: CondensedJoint, loads_N=(5.0, 20.0), axis_sign: float = -1.0, *,
                penetration_tol: float, max_iter: int = 100, initial_gap_m: float | None = None,
                area_gap_rel: float = 0.0, level_tangents: bool = False, rtol: float = 1e-9) -> JointResponse:
    """Press node b along ∓z (``axis_sign``) with the eq. 1 force levels and measure its compliances.

    ``penetration_tol`` (m): largest penetration accepted by the augmented Lagrangian (choose ≪ the
    approach at the smallest load, e.g. 1e-3 of the analytical one); ``initial_gap_m``: the points whose
    initial gap is below it start closed (ball in seat: half the Hertz approach at the preload, i.e. the
    Hertz patch r ≤ a(F_5)); ``None``: the points within the clearance. ``area_gap_rel``: the stick
    tangent sticks the closed points and every candidate point whose final gap is below this fraction of
    the axial increment u(F_20) − u(F_5) (the contact area; 0: the closed points only). ``rtol``: converged
    when ‖r‖ ≤ rtol F_max with an unchanged active set. ``level_tangents``: also return the stick tangent
    stiffness at every load level (a force ladder: :mod:`femcheck.fe_device.joint_laws`; the contact area of
    each level with the same absolute gap tolerance)."""
    from femcheck.fe.contact.condensed_solver import solve_condensed_contact

    t0 = time.perf_counter()
    loads = tuple(float(F) for F in loads_N)
    Fmax = max(loads)
    n = model.S.shape[0]
    # the eq. 1 load path: node b moves along the joint axis only (the leg holds its other components),
    # frictionless normal contact (under a pure axial load friction does no work on a symmetric patch)
    held = np.delete(model.ref, 2)
    keep = np.setdiff1d(np.arange(n), held)
    ax = int(np.searchsorted(keep, model.ref[2]))
    f = np.zeros(keep.size)
    f[ax] = axis_sign * Fmax
    B = sp.vstack([p.B_n[:, keep] for p in model.pairs], format="csr")
    g0 = np.concatenate([p.g0 for p in model.pairs])
    eps = np.concatenate([p.penalty_n for p in model.pairs])
    w = np.concatenate([p.weights for p in model.pairs])
    sizes = np.cumsum([0] + [p.n_points for p in model.pairs])

    def point_info(idx):
        out = []
        for k in np.asarray(idx)[:50]:
            j = int(np.searchsorted(sizes, k, side="right") - 1)
            pr = model.pairs[j]
            out.append({"pair": pr.name, "point": int(k - sizes[j]), "x_m": pr.points[k - sizes[j]].tolist()})
        return out

    # Hertz-predicted active set: every candidate point within the clearance (plus a tiny margin) starts
    # closed (the candidates are the loaded lines only, :func:`_candidates`)
    closure = model.clearance_m * 2.0 + 1e-3 * model.contact_h_m if initial_gap_m is None else float(initial_gap_m)
    res = solve_condensed_contact(model.S[np.ix_(keep, keep)], f, B, g0, eps, w, [F / Fmax for F in loads],
                                  initial_closed=g0 <= closure, penetration_tol=penetration_tol, max_iter=max_iter, rtol=rtol,
                                  point_info=point_info)
    u = axis_sign * res.u[:, ax]
    sec = float((u[-1] - u[0]) / (loads[-1] - loads[0]))
    closed = [res.closed[-1][sizes[j]:sizes[j + 1]] for j in range(len(model.pairs))]
    if model.recover is not None and model.candidate_points < model.contact_points:
        u_full = np.zeros(n)
        u_full[keep] = res.u[-1]
        gaps = model.recover(u_full)
        # a dropped point violates the candidate band when it penetrates more than it did at the start
        # (initial facet-chord noise, accepted by the geometry check, is not a contact the band missed)
        growth = [-g - np.maximum(-p0.g0, 0.0) for g, p0 in zip(gaps, model.full_pairs)]
        j = int(np.argmax([float(x.max()) for x in growth]))
        k = int(np.argmax(growth[j]))
        pen = float(growth[j][k])
        pw = model.full_pairs[j]
        where = {"pair": pw.name, "point": k, "x_m": pw.points[k].tolist(), "g0_m": float(pw.g0[k])}
        log.info("%s: largest penetration growth over all contact points %.3g m at %s", model.joint, pen, where)
        if pen > 10.0 * penetration_tol:
            raise CandidateBandError(f"{model.joint} joint: a contact point outside the candidate band penetrates "
                                     f"by {pen:.3g} m ({where})", list(res.residual_history),
                                     {"penetration_m": pen, "point": where})
    # the contact area of the test state: the closed points and the points whose gap is within
    # ``area_gap_rel`` of the approach increment (GPTS on P2 facets closes only a subset of the Gauss points
    # of the patch, the others open by round-off-size gaps; the stick state sticks the whole area)
    gap_tol = area_gap_rel * abs(float(u[-1] - u[0])) if area_gap_rel > 0 else -np.inf

    def contact_area(k):
        g = g0 + B @ res.u[k]
        return [res.closed[k][sizes[j]:sizes[j + 1]] | (g[sizes[j]:sizes[j + 1]] <= gap_tol)
                for j in range(len(model.pairs))]
    area = contact_area(-1)
    log.info("%s: %d closed points, contact area %d points (gap <= %.3g m)", model.joint,
             sum(int(c.sum()) for c in closed), sum(int(c.sum()) for c in area), gap_tol)
    tangent, stiffness = _tangent(model, area)
    per_level = None
    if level_tangents:
        per_level = np.stack([_tangent(model, contact_area(k))[1] for k in range(len(loads) - 1)] + [stiffness])
    return JointResponse(model.joint, loads, u, sec, tangent, stiffness, int(sum(int(c.sum()) for c in closed)),
                         res.iterations, res.factorizations, res.augmentations,
                         model.dofs, model.free_dofs, model.retained, time.perf_counter() - t0 + model.condense_s,
                         model.condense_s, res.line_search_cuts, res.stabilized_iterations,
                         res.stabilization_force_share, float(res.residual_history[-1]) / Fmax, per_level,
                         res.low_rank_updates)


def _tangent(model: CondensedJoint, closed_sets) -> np.ndarray:
    """6 x 6 stick compliance of node b: the condensed matrix plus ε_n on the closed points and ε_t on the
    same points held stuck (the Mindlin stick state the analytical laws describe)."""
    A = model.S.copy()
    for p, closed in zip(model.pairs, closed_sets):
        if closed.any():
            Bn = p.B_n[closed]
            A += (Bn.T @ sp.diags(p.penalty_n[closed] * p.weights[closed]) @ Bn).toarray()
        stick = closed
        if stick.any():
            rows = np.flatnonzero(np.repeat(stick, 2))
            Bt = p.B_t[rows]
            w = np.repeat(p.penalty_t[stick] * p.weights[stick], 2)
            A += (Bt.T @ sp.diags(w) @ Bt).toarray()
    ref = model.ref
    o = np.setdiff1d(np.arange(A.shape[0]), ref)
    Aoo = A[np.ix_(o, o)]
    Aor = A[np.ix_(o, ref)]
    try:
        X = np.linalg.solve(Aoo, Aor)
    except np.linalg.LinAlgError:
        X = np.linalg.lstsq(Aoo, Aor, rcond=None)[0]
    Kb = A[np.ix_(ref, ref)] - Aor.T @ X
    log.info("%s: 6 x 6 tangent stiffness asymmetry before symmetrising %.3g (Maxwell-Betti, round-off)",
             model.joint, float(np.abs(Kb - Kb.T).max() / np.abs(Kb).max()))
    Kb = 0.5 * (Kb + Kb.T)
    w, V = np.linalg.eigh(Kb)
    tol = 1e-9 * max(float(w.max()), 1e-300)
    Cb = np.zeros((6, 6))
    for k in range(6):
        if w[k] > tol:
            Cb += np.outer(V[:, k], V[:, k]) / w[k]
    for k in range(6):  # a mechanism of the contact (no stiffness): infinite compliance where it moves
        if w[k] <= tol:
            big = np.abs(V[:, k]) > 1e-3
            Cb[np.ix_(big, big)] = np.inf
    return Cb, Kb


def contact_start(case, joint: str, loads_N) -> tuple[float, float | None]:
    """(penetration tolerance (m), initial gap (m) below which points start closed, or None) of the contact
    FE of ``joint`` loaded over ``loads_N`` (N), from the FE's own expected compliance
    (:mod:`femcheck.fe_device.contact_scales`, never the law under test): penetration accepted 1e-3 of the
    expected approach at the smallest load; the ball starts from the expected Hertz patch of that load,
    g0 ≤ δ(F_min) / 2 ⇔ r ≤ a(F_min)."""
    from femcheck.fe_device.contact_scales import device_springs
    sp_ = device_springs(case)
    F0 = float(min(loads_N))
    tol = 1e-3 * sp_.axial_compliance(joint, loads_N) * F0
    start = 0.5 * float(sp_.ball_approach(F0)) if joint == "spherical" else None
    return tol, start


def analytical_compliance(case, joint: str, loads_N=(5.0, 20.0)) -> np.ndarray:
    """6 x 6 compliance of the closed-form joint laws (seed 000 §4.4.1) in the joint frame, SI.

    spherical: axial = Hertz eq. 1 secant (δ_H(F20) − δ_H(F5)) / (F20 − F5) (Johnson eq. 4.23),
    lateral = Mindlin stick 1/(8 G* a) (Johnson eq. 7.32), tilt = 1/(8 G* a R_b²), spin = 3/(16 G* a³);
    universal (frame B): lateral x, y = c_UC (Hertz line contact), axial z = c_UC + c_UB (line contact
    plus pin bending, seed 000 eqs. 36–41), rotations about a1, a2 = 1/(k_line r_pin²) (stick),
    spin about z = 0 (tied in the analytical model).
    """
    from femcheck.chain import device_parameters
    from femcheck.fe_device.joint_friction import joint_friction
    from femcheck.fe_device.loads import hertz_approach

    # the law under test: E*, R*, K_UC and K_UB as the analytical model has them (device_parameters), also
    # for the Mindlin stick terms that follow from the Hertz radius and the line contact
    p = device_parameters(case)
    E_star, R_star = float(np.squeeze(p.E_star_sp)), float(np.squeeze(p.R_star_sp))
    c_uc, c_ub = float(np.squeeze(p.c_uc)), float(np.squeeze(p.c_ub))
    fr = dataclasses.replace(joint_friction(case), E_star_Pa=E_star, R_star_m=R_star, K_uc_N_per_m=1.0 / c_uc)
    F0, F1 = float(min(loads_N)), float(max(loads_N))
    C = np.zeros((6, 6))
    if joint == "spherical":
        d = hertz_approach(np.array([F0, F1]), E_star, R_star)
        a = float(fr.contact_radius(F1))
        kt, ks, _ = fr.stick_stiffness(np.array([F1]))
        C[2, 2] = (d[1] - d[0]) / (F1 - F0)
        C[0, 0] = C[1, 1] = 1.0 / (8.0 * fr.G_star_Pa * a)
        C[3, 3] = C[4, 4] = 1.0 / float(kt[0])
        C[5, 5] = 1.0 / float(ks[0])
    else:
        _, _, kp = fr.stick_stiffness(np.array([F1]))
        C[0, 0] = C[1, 1] = c_uc
        C[2, 2] = c_uc + c_ub
        C[3, 3] = C[4, 4] = 1.0 / float(kp[0])
    return C


def error_pct(fe, analytical: np.ndarray) -> dict:
    """Per component: 100 (FE − analytical) / analytical; None where the analytical law is 0 or either
    value is infinite (a released or tied component). ``fe``: (6,) component compliances or a 6 x 6."""
    fe = np.asarray(fe, float)
    fe = np.diag(fe) if fe.ndim == 2 else fe
    out = {}
    for k, name in enumerate(COMPONENTS):
        a, f = float(analytical[k, k]), float(fe[k])
        out[name] = None if (a == 0 or not math.isfinite(a) or not math.isfinite(f)) else 100.0 * (f - a) / a
    return out
