"""Contact FE of the spherical joint alone vs its Hertz model (issue 6, detailed level, partial).

Model: the ``geometry.spherical_joint`` part (steel ball on the polymer seat of the case, flat seat as
in the paper), P2 tetrahedra, materials per body from the case. The seat bottom is clamped (it sits on
the slider); the ball cap toward the link is tied by a rigid coupling (RBE2) to the reference node B at
the ball centre, whose rotations and lateral translations are held, so B moves along the seat normal
only. A force F along −z on B presses the ball into the seat; penalty contact with augmented-Lagrangian
updates and modified Newton–Raphson (``femcheck.fe.newton.solve_contact``), frictionless normal contact.

Compared quantity: the approach δ(F) = −u_z(B) at the eq. 1 load levels (5 N and 20 N, and 15 N), and
the eq. 1 increment δ(20) − δ(5) against the Hertz closed form (Johnson eq. 4.23, CONVENTIONS.md §5)
δ_H(F) = (3F / (4 E* √R*))^{2/3}. The FE contains, besides the Hertz approach of two half-spaces,
the bulk compression of the finite seat disk and of the ball between the contact and the coupling cap,
so it is expected to be somewhat softer; the ratio is what the detailed analytical model leaves out.
"""
from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np

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


def spherical_joint_contact(case, size_m: float | None = None, loads=LOADS_N, penalty_factor: float = 100.0) -> JointContactResult:
    """Solve the ball-on-seat contact under ``loads`` (N, ascending) and compare with Hertz (module doc)."""
    from femcheck.compliance.hertz_point_contact import effective_modulus, effective_radius
    from femcheck.fe import constraints as cs
    from femcheck.fe.contact.pairing import default_penalty, pair_surfaces
    from femcheck.fe.elasticity import assemble_stiffness, dof_triplets, vector_basis
    from femcheck.fe.newton import ContactProblem, solve_contact
    from femcheck.fe_device.loads import hertz_approach
    from geometry import spherical_joint

    t0 = time.perf_counter()
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
    con = cs.combine(cs.clamp(ndof, basis.get_dofs("sj_seat_mount").all()),
                     cs.rigid_coupling(ndof, ref, np.zeros(3), pts, trip),
                     cs.clamp(ndof, ref[[0, 1, 3, 4, 5]]))
    slave, master = mesh.boundaries["sj_seat_contact"], mesh.boundaries["sj_ball_contact"]
    eps = default_penalty(mesh, slave, sj.seat_material.E_Pa, penalty_factor)
    pair = pair_surfaces(basis, slave, master, penalty_n=eps, friction=0.0, name="sj", ndof=ndof)
    Fmax = max(loads)
    f = np.zeros(ndof)
    f[ref[2]] = -Fmax
    problem = ContactProblem(K=K, f=f, constraints=con, pairs=(pair,))
    Es = float(effective_modulus(sj.ball_material.E_Pa, sj.ball_material.nu, sj.seat_material.E_Pa, sj.seat_material.nu))
    Rs = float(effective_radius(sj.ball_radius_m, sj.seat_curvature_1_per_m))
    dh = hertz_approach(np.asarray(loads, float), Es, Rs)
    # penetration accepted: 0.1 % of the smallest Hertz approach (the compared quantity)
    res = solve_contact(problem, [F / Fmax for F in loads], initial_closure=max(float(pair.g0.min()), 0.0) + 1e-12,
                        penetration_tol=1e-3 * float(dh.min()))
    delta = np.array([-s.u[ref[2]] for s in res.steps])
    return JointContactResult(tuple(float(F) for F in loads), delta, dh, int(con.nfree),
                              int(sum(res.iterations_per_step)), time.perf_counter() - t0)

