"""Contact FE of the spherical joint alone vs its Hertz model.

Model: the ``geometry.spherical_joint`` part (steel ball on the polymer seat of the case, flat seat as
in the paper), P2 tetrahedra, materials per body from the case. The seat bottom is clamped (it sits on
the slider); the ball cap toward the link is tied by a rigid coupling (RBE2) to the reference node B at
the ball centre, whose rotations and lateral translations are held, so B moves along the seat normal
only. A force F along −z on B presses the ball into the seat; penalty contact with augmented-Lagrangian
updates and modified Newton–Raphson (``femcheck.fe.newton.solve_contact``), frictionless normal contact.

Compared quantity: the approach δ(F) = −u_z(B) at the eq. 1 load levels (5 N and 20 N, and 15 N), and
the eq. 1 increment δ(20) − δ(5) against the Hertz closed form (Johnson eq. 4.23, docs/conventions.md §5)
δ_H(F) = (3F / (4 E* √R*))^{2/3}. The FE contains, besides the Hertz approach of two half-spaces,
the bulk compression of the finite seat disk and of the ball between the contact and the coupling cap,
so it is expected to be somewhat softer; the ratio is what the detailed analytical model leaves out.
"""
from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np
import scipy.sparse as sp

log = logging.getLogger(__name__)

LOADS_N = (5.0, 15.0, 20.0)


@dataclasses.dataclass(frozen=True)
class JointContactResult:
    """Approach δ (m) per load (N) from FE and from Hertz, DOFs, Newton iterations, wall time (s)."""

    loads_N: tuple
    delta_fe_m: np.ndarray
    delta_hertz_m: np.ndarray
    dofs: int
    iterations: int
    seconds: float

    @property
    def increment_ratio(self) -> float:
        """(δ_FE(20) − δ_FE(5)) / (δ_H(20) − δ_H(5)) (eq. 1 protocol)."""
        i5, i20 = self.loads_N.index(5.0), self.loads_N.index(20.0)
        return float((self.delta_fe_m[i20] - self.delta_fe_m[i5]) / (self.delta_hertz_m[i20] - self.delta_hertz_m[i5]))


@dataclasses.dataclass(frozen=True)
class _BallSeatModel:
    """Assembled ball-on-seat contact model: stiffness, reference node B (6 DOFs), base constraints, pair."""

    K: object
    ndof: int
    ref: np.ndarray
    base_constraints: object
    pair: object
    E_star: float
    R_star: float
    dofs: int
    cap_points: np.ndarray
    cap_dofs: np.ndarray


def _ball_seat_model(case, size_m, *, friction: float, penalty_factor: float) -> _BallSeatModel:
    """Mesh, stiffness, seat clamp, ball-cap coupling to B and the contact pair (module doc)."""
    from femcheck.fe import constraints as cs
    from femcheck.fe_device.contact_scales import device_springs
    from femcheck.fe.contact.pairing import default_penalty, pair_surfaces
    from femcheck.fe.elasticity import assemble_stiffness, dof_triplets, vector_basis
    from geometry import spherical_joint

    sj = case.spherical_joint
    pm = spherical_joint.build(case, size_m, seat="flat")
    mesh = pm.to_skfem()
    basis = vector_basis(mesh, 2)
    mats = {"ball": sj.ball_material, "seat": sj.seat_material}
    names = [b.name for b in pm.bodies]
    E = np.array([mats["ball" if "ball" in names[k] else "seat"].E_Pa for k in pm.body_of_tet])
    nu = np.array([mats["ball" if "ball" in names[k] else "seat"].nu for k in pm.body_of_tet])
    K = assemble_stiffness(basis, E, nu)
    ndof, ref = cs.append_reference_nodes(basis.N, 1)
    ref = ref[0]
    pts, trip = dof_triplets(basis, basis.get_dofs("sj_ball_link").all())
    base = cs.combine(cs.clamp(ndof, basis.get_dofs("sj_seat_mount").all()),
                      cs.rigid_coupling(ndof, ref, np.zeros(3), pts, trip))
    slave, master = mesh.boundaries["sj_seat_contact"], mesh.boundaries["sj_ball_contact"]
    eps = default_penalty(mesh, slave, sj.seat_material.E_Pa, penalty_factor)
    pair = pair_surfaces(basis, slave, master, penalty_n=eps, friction=friction, name="sj", ndof=ndof)
    springs = device_springs(case)   # the FE's own contact scale (tolerances), not the law it is compared with
    return _BallSeatModel(K, ndof, ref, base, pair, springs.E_star_sp, springs.R_star_sp, int(basis.N), pts, trip)


def spherical_joint_contact(case, size_m: float | None = None, loads=LOADS_N, penalty_factor: float = 100.0) -> JointContactResult:
    """Solve the ball-on-seat contact under ``loads`` (N, ascending) and compare with Hertz (module doc)."""
    from femcheck.fe import constraints as cs
    from femcheck.fe.newton import ContactProblem, solve_contact
    from femcheck.fe_device.loads import hertz_approach

    t0 = time.perf_counter()
    m = _ball_seat_model(case, size_m, friction=0.0, penalty_factor=penalty_factor)
    ref = m.ref
    con = cs.combine(m.base_constraints, cs.clamp(m.ndof, ref[[0, 1, 3, 4, 5]]))
    Fmax = max(loads)
    f = np.zeros(m.ndof)
    f[ref[2]] = -Fmax
    problem = ContactProblem(K=m.K, f=f, constraints=con, pairs=(m.pair,))
    from femcheck.compliance.hertz_point_contact import effective_modulus, effective_radius
    sj = case.spherical_joint
    # the compared law: Hertz with the analytical model's E* and R*
    dh = hertz_approach(np.asarray(loads, float), effective_modulus(sj.ball_material.E_Pa, sj.ball_material.nu,
                                                                    sj.seat_material.E_Pa, sj.seat_material.nu),
                        effective_radius(sj.ball_radius_m, sj.seat_curvature_1_per_m))
    # penetration accepted: 0.1 % of the smallest approach the FE expects (its own estimate, not the law)
    res = solve_contact(problem, [F / Fmax for F in loads], initial_closure=max(float(m.pair.g0.min()), 0.0) + 1e-12,
                        penetration_tol=1e-3 * float(hertz_approach(min(loads), m.E_star, m.R_star)))
    delta = np.array([-s.u[ref[2]] for s in res.steps])
    return JointContactResult(tuple(float(F) for F in loads), delta, dh, int(con.nfree),
                              int(sum(res.iterations_per_step)), time.perf_counter() - t0)


@dataclasses.dataclass(frozen=True)
class JointTiltResult:
    """Moment–rotation of the ball in its seat under proportional loading (SI).

    ``load_factors`` (n,); ``normal_force_N`` (n,) contact force; ``rotation_rad`` (n,) imposed tilt of B
    about x; ``moment_Nm`` (n,) reaction moment about x at B; ``friction`` μ; ``ball_radius_m`` R;
    ``slip_fraction`` (n,) share of the closed contact points that slide; ``dofs``, ``iterations``,
    ``seconds``.
    """

    load_factors: np.ndarray
    normal_force_N: np.ndarray
    rotation_rad: np.ndarray
    moment_Nm: np.ndarray
    friction: float
    ball_radius_m: float
    slip_fraction: np.ndarray
    dofs: int
    iterations: int
    seconds: float

    @property
    def slip_radius_ratio(self) -> np.ndarray:
        """|M| / (μ N R): 1 when the whole contact slides (the moment is μ N R), < 1 while parts stick."""
        return np.abs(self.moment_Nm) / (self.friction * self.normal_force_N * self.ball_radius_m)

    @property
    def secant_stiffness_Nm_per_rad(self) -> np.ndarray:
        return np.abs(self.moment_Nm) / np.abs(self.rotation_rad)


def spherical_joint_tilt(case, normal_force_N: float, rotation_rad: float, *, friction: float,
                         size_m: float | None = None, load_steps=(0.25, 0.5, 0.75, 1.0),
                         penalty_factor: float = 100.0, condensed: bool = True) -> JointTiltResult:
    """Tilt the ball about x through B while pressing it into the seat, both in proportion (N, rad).

    This is how a joint of the device is loaded under a monotonic TCP load: its force and its rotation
    grow together. B's lateral translations are held (the leg holds the ball centre), the force
    ``normal_force_N`` acts along −z (into the seat) and the tilt θ_x is imposed; Coulomb friction μ acts
    in the contact (penalty + augmented Lagrangian, :mod:`femcheck.fe.contact.coulomb_friction`).

    Physics: frictionless contact forces on a sphere are normal to it and pass through its centre, so the
    joint carries no moment about B; with friction the contact point (at distance R from B) resists the
    tilt with a tangential force ≤ μ N, so the moment is bounded by the slip moment μ N R; below it the
    contact sticks (Mindlin tangential stiffness, rotational stiffness ≈ 8 G* a R²).

    ``condensed`` (default): the bodies are condensed exactly onto the contact points of the Hertz band and the
    reference node B (:func:`_tilt_condensed`), and the same modified Newton–Raphson with friction runs on that
    small system; False: on the whole mesh (the same answer to the solver tolerance, ~10x slower).
    """
    from femcheck.fe import constraints as cs
    from femcheck.fe.newton import ContactProblem, solve_contact
    from femcheck.fe_device.loads import hertz_approach

    t0 = time.perf_counter()
    m = _ball_seat_model(case, size_m, friction=friction, penalty_factor=penalty_factor)
    if condensed:
        return _tilt_condensed(case, m, normal_force_N, rotation_rad, friction, load_steps, t0)
    ref = m.ref
    con = cs.combine(m.base_constraints, cs.clamp(m.ndof, ref[[0, 1, 4, 5]]),
                     cs.clamp(m.ndof, ref[[3]], values=float(rotation_rad)))
    f = np.zeros(m.ndof)
    f[ref[2]] = -float(normal_force_N)
    problem = ContactProblem(K=m.K, f=f, constraints=con, pairs=(m.pair,))
    dh = float(hertz_approach(normal_force_N * min(load_steps), m.E_star, m.R_star))
    res = solve_contact(problem, list(load_steps), initial_closure=max(float(m.pair.g0.min()), 0.0) + 1e-12,
                        penetration_tol=1e-3 * dh, max_iter=120)
    from femcheck.fe.contact import status as st
    lf = np.array([s.load_factor for s in res.steps])
    N = np.array([s.pairs[0].force(m.pair) for s in res.steps])
    # moment about B that the ball cap exerts on the link: Σ r_i × (reaction at cap node i), x component
    M = np.array([np.cross(m.cap_points, res.reactions(problem, k)[m.cap_dofs]).sum(axis=0)[0]
                  for k in range(len(res.steps))])
    slip = []
    for s in res.steps:
        closed = s.pairs[0].status != st.OPEN
        slip.append(float(np.mean(s.pairs[0].status[closed] == st.SLIDE)) if closed.any() else 0.0)
    return JointTiltResult(lf, N, lf * float(rotation_rad), M, float(friction), float(case.spherical_joint.ball_radius_m),
                           np.array(slip), int(con.nfree), int(sum(res.iterations_per_step)), time.perf_counter() - t0)


#: ball-in-seat tilt: contact points whose initial gap is within this many Hertz approaches at the full load of the
#: smallest gap are kept in the condensed contact iterations (the gap grows as r² / (2 R*) and the patch edge a has g0 = δ_H / 2,
#: so 2 δ_H keeps r ≤ 2 a); every dropped point is checked to stay open after the solve
TILT_BAND = 2.0


def _slice_pair(pair, keep: np.ndarray, B_n, B_t):
    """``pair`` restricted to the points ``keep`` (bool (m,)) with the operators ``B_n`` (k, n_r), ``B_t``
    (2k, n_r) of the condensed unknowns."""
    per_point = {f.name: getattr(pair, f.name)[keep] for f in dataclasses.fields(pair)
                 if isinstance(getattr(pair, f.name), np.ndarray) and getattr(pair, f.name).shape[:1] == (pair.n_points,)}
    return dataclasses.replace(pair, B_n=B_n, B_t=B_t, **per_point)


def _tilt_condensed(case, m: _BallSeatModel, normal_force_N: float, rotation_rad: float, friction: float,
                    load_steps, t0: float) -> JointTiltResult:
    """:func:`spherical_joint_tilt` on the bodies condensed onto the Hertz-band contact DOFs and node B.

    The constrained stiffness K_q = Tᵀ K T (seat clamped, ball cap tied to B, B's six DOFs free) is reduced
    exactly to the DOFs that the contact operators of the points with g0 ≤ ``TILT_BAND`` δ_H(F) touch plus B
    (S = K_rr − K_ri K_ii⁻¹ K_ir, :func:`femcheck.fe.schur_complement.condense`: linear bodies, so the
    condensation is exact). B's held components and the imposed tilt become constraints of the condensed
    system; the contact iterations (:func:`femcheck.fe.newton.solve_contact`, friction, augmented Lagrangian)
    then factorize a matrix of a few hundred unknowns instead of the ~40,000 of the mesh. The moment about x
    is the reaction of the imposed θ_x: (S u)_θx = Σ (x_i × r_i)_x over the cap nodes (the coupling's virtual
    work). After the solve the interior is recovered from the same factorization and every dropped point
    must still be open (:class:`femcheck.errors.ConvergenceError` otherwise)."""
    from femcheck.errors import ConvergenceError
    from femcheck.fe import constraints as cs
    from femcheck.fe.contact import status as st
    from femcheck.fe.newton import ContactProblem, solve_contact
    from femcheck.fe.schur_complement import condense
    from femcheck.fe_device.loads import hertz_approach

    C = m.base_constraints
    T = C.T
    Kq = sp.csr_matrix(T.T @ (cs.pad(sp.csr_matrix(m.K), m.ndof) @ T))
    pair = m.pair
    Bn_q, Bt_q = sp.csr_matrix(pair.B_n @ T), sp.csr_matrix(pair.B_t @ T)
    dh_max = float(hertz_approach(float(normal_force_N), m.E_star, m.R_star))
    chord = max(-float(pair.g0.min()), 0.0)
    # measured from the first point to touch (a coarse facet mesh may start with every gap open)
    keep = pair.g0 <= max(float(pair.g0.min()), 0.0) + TILT_BAND * dh_max + 2.0 * chord
    rows_t = np.flatnonzero(np.repeat(keep, 2))
    col_of_ref = {int(d): int(np.flatnonzero(C.free == d)[0]) for d in m.ref}  # B's DOFs are free in K_q
    ref_q = np.array([col_of_ref[int(d)] for d in m.ref])
    r = np.unique(np.concatenate([Bn_q[keep].indices, Bt_q[rows_t].indices, ref_q]))
    cond = condense(Kq, r)
    pos = np.full(Kq.shape[0], -1)
    pos[r] = np.arange(r.size)
    red = _slice_pair(pair, keep, sp.csr_matrix(Bn_q[keep][:, r]), sp.csr_matrix(Bt_q[rows_t][:, r]))
    b = pos[ref_q]                                   # B's u_x, u_y, u_z, θ_x, θ_y, θ_z in the condensed unknowns
    con = cs.combine(cs.clamp(r.size, b[[0, 1, 4, 5]]), cs.clamp(r.size, b[[3]], values=float(rotation_rad)))
    f = np.zeros(r.size)
    f[b[2]] = -float(normal_force_N)
    problem = ContactProblem(K=sp.csr_matrix(cond.S), f=f, constraints=con, pairs=(red,))
    dh = float(hertz_approach(normal_force_N * min(load_steps), m.E_star, m.R_star))
    pen_tol = 1e-3 * dh
    res = solve_contact(problem, list(load_steps), initial_closure=max(float(red.g0.min()), 0.0) + 1e-12,
                        penetration_tol=pen_tol, max_iter=120)
    dropped = ~keep
    if dropped.any():
        for k, s in enumerate(res.steps):
            gap = pair.g0[dropped] + Bn_q[dropped] @ cond.extend(s.u)
            if float(gap.min()) < -pen_tol:
                i = int(np.argmin(gap))
                raise ConvergenceError(f"ball tilt: a contact point outside the Hertz band ({TILT_BAND:g} approaches) "
                                       f"closes at load step {k} (gap {float(gap[i]):.3g} m at "
                                       f"{pair.points[dropped][i].tolist()}); raise TILT_BAND", list(res.residual_history),
                                       {"gap_m": float(gap[i])})
    cond.free()
    lf = np.array([s.load_factor for s in res.steps])
    N = np.array([s.pairs[0].force(red) for s in res.steps])
    M = np.array([res.reactions(problem, k)[b[3]] for k in range(len(res.steps))])
    slip = []
    for s in res.steps:
        closed = s.pairs[0].status != st.OPEN
        slip.append(float(np.mean(s.pairs[0].status[closed] == st.SLIDE)) if closed.any() else 0.0)
    log.info("ball tilt (mu %.3g): %d of %d contact points in the band, %d -> %d unknowns, %d iterations, %.1f s",
             friction, int(keep.sum()), pair.n_points, Kq.shape[0], r.size, sum(res.iterations_per_step),
             time.perf_counter() - t0)
    return JointTiltResult(lf, N, lf * float(rotation_rad), M, float(friction), float(case.spherical_joint.ball_radius_m),
                           np.array(slip), int(Kq.shape[0]) - 5, int(sum(res.iterations_per_step)), time.perf_counter() - t0)
