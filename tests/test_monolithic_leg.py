"""Monolithic leg check: the leg load, the placement and assembly of the bodies in the link
frame, and (slow) one complete leg as one contact model vs the substructured leg with the FE-measured joints."""
from __future__ import annotations

import numpy as np
import pytest

from femcheck.fe_device import monolithic_leg as ml


def test_leg_load_is_the_most_compressed_leg(case):
    """Released-joint statics: the chosen leg carries the most negative f_i; the eq. 1 levels keep 20 N / 5 N."""
    from femcheck.fe_device.joint_check import leg_forces
    load = ml.leg_load(case, "P0")
    f = leg_forces(case, "P0")
    assert load.loads_N[1] == pytest.approx(-f[:, 1, :].min(), rel=1e-12)  # same statics, same numbers
    L = case.loads
    # statics is linear in the TCP load
    assert load.loads_N[1] / load.loads_N[0] == pytest.approx((L.detailed_preload_N + L.detailed_test_N)
                                                              / L.detailed_preload_N, rel=1e-12)
    # the link leaves the rail at tan(angle) > μ = 0.1: a flat seat normal to the rail could not hold the ball
    assert np.tan(np.radians(load.inclination_deg)) > 3 * case.solid.spherical_joint.friction
    # the link frame: z along u, x = a1 normal to the rail z_U (docs/conventions.md §2); proper rotations
    assert np.allclose(load.R_B[:, 2], load.u, atol=1e-14) and abs(load.R_B[2, 0]) < 1e-14
    assert np.linalg.det(load.R_B) == pytest.approx(1.0, abs=1e-12)


def test_placed_guideway_is_the_guideway_super_element(case):
    """The guideway meshed into the link frame, clamped and tied to B_g, gives the super-element's compliance
    along u (elasticity is frame-invariant: round-off), and its K annihilates the rigid modes of that frame."""
    from femcheck.fe.elasticity import dof_triplets
    from femcheck.fe.linear_solver import factorize
    from femcheck.fe_device.parts import guideway_element
    load = ml.leg_load(case, "P0")
    size = 2 * case.solid.mesh.guideway_size_m
    (pm,) = ml.place_bodies(case, load, {"guideway": size}, bodies=("guideway",))
    asm = ml.assemble_leg(case, [pm], (), {"B_g": (np.zeros(3), ("lg_slider",))})
    # rigid modes of the placed mesh (no constraints): K r = 0 to round-off of the stiffness scale
    pts, trip = dof_triplets(asm.basis)
    for k in range(6):
        r = np.zeros(asm.basis.N)
        e = np.zeros(3)
        e[k % 3] = 1.0
        r[trip] = e if k < 3 else np.cross(e, pts)
        Kr = asm.K @ r
        assert np.abs(Kr).max() < 1e-9 * abs(asm.K).max() * np.abs(r).max()
    # clamp at A and push B_g along −u (the leg in compression): displacement along −u
    asm = ml.assemble_leg(case, [pm], ("lg_clamp",), {"B_g": (np.zeros(3), ("lg_slider",))})
    con = asm.constraints
    f = np.zeros(asm.ndof)
    f[asm.refs["B_g"][2]] = -1.0
    q = factorize(con.reduce_matrix(asm.K), symmetric=True).solve(con.reduce_vector(f))
    u = con.expand(q)
    delta = -u[asm.refs["B_g"][2]]
    lg = guideway_element(case, load.slider_m, "solid", size)
    uA = load.R_A.T @ load.u
    # same mesh, rotated frame: agreement to solver round-off
    assert delta == pytest.approx(float(uA @ np.linalg.inv(lg.K)[:3, :3] @ uA), rel=1e-7)
    # and the Euler–Bernoulli cantilever within 2 % (shear and clamp effects at L/b ≈ 15, coarse P2 mesh:
    # measured −0.55 %)
    beam = guideway_element(case, load.slider_m, "beam")
    assert delta == pytest.approx(float(uA @ np.linalg.inv(beam.K)[:3, :3] @ uA), rel=0.02)


def test_part_sizes_follow_the_mesh_level(case):
    """Every body scales with the level's factor; a bad level is a one-line error naming the option."""
    from femcheck.errors import FemcheckError
    c, d = ml.part_sizes(case, "coarse"), ml.part_sizes(case, "default")
    assert all(c[k] == pytest.approx(2 * d[k]) for k in d)
    with pytest.raises(FemcheckError, match="--mesh"):
        ml.part_sizes(case, "huge")


def _hub_tie_half_length(pm, centre):
    """Largest |x − centre| of the uj_hub tie nodes on pin a1's axis plane (pin a1 lies along x)."""
    x = pm.points[pm.regions["uj_hub"].nodes] - centre
    return float(np.abs(x[np.abs(x[:, 1]) < 1e-9, 0]).max())


def test_leg_universal_joint_is_the_joint_fe_mesh_and_ties_the_whole_hub(case):
    """The monolithic leg meshes its universal joint as the joint FE does at the same level: the rigid hub
    ties exactly ±hub_half_length_m (hub ends are element levels; the 2 mm mesh without them tied ±1.8 mm
    only, a ≈ 7 % stiffer joint), and the nodes are the joint FE's mesh moved to C (same mesh, so the
    joints' own discretisation cannot differ between the two leg models)."""
    from femcheck.fe_device.joint_fe import level_mesh_options
    from geometry import universal_joint
    load = ml.leg_load(case, "P0")
    C = np.array([0.0, 0.0, case.geometry.proximal_link_length_m])
    (pm,) = ml.place_bodies(case, load, ml.part_sizes(case, "coarse"), bodies=("universal_joint",), mesh="coarse")
    hub = float(case.solid.universal_joint.hub_half_length_m)
    assert _hub_tie_half_length(pm, C) == pytest.approx(hub, abs=1e-12)  # exact: the hub ends are mesh levels
    size, opts = level_mesh_options(case, "universal", "coarse", max(load.loads_N))
    assert opts["hub_levels"] is True
    ref = universal_joint.build(case, size, **opts)
    assert pm.points.shape == ref.points.shape and np.allclose(pm.points - C, ref.points, rtol=0, atol=1e-15)
    # the same mesh without the hub levels (what the leg used before): the tie falls short of the hub ends
    short = universal_joint.build(case, size, **{**opts, "hub_levels": False})
    assert _hub_tie_half_length(short, np.zeros(3)) < 0.95 * hub


@pytest.mark.slow
@pytest.mark.parametrize("point", ["P0", "P5"])
def test_monolithic_leg_agrees_with_substructured_leg(case, point):
    """Issue 14 part 4: the displacement of C_i under the leg force, one contact model vs the super-elements in
    series with the joints' contact FE, agrees within 2 % (eq. 1 increment and the F20 value, and the joints'
    share of the increment alone)."""
    r = ml.check_monolithic_leg(case, point, "coarse")
    assert r.residual_rel < 1e-6  # converged (the solver raises otherwise); force balance to 1e-6 of F20
    assert r.stabilization_force_share < 1e-6  # no force through the iteration-matrix spring
    assert abs(r.relative_difference) <= ml.AGREEMENT_REL
    assert abs(r.relative_difference_total) <= ml.AGREEMENT_REL
    # the stronger form: the joints' share alone (the guideway, same mesh in both, is most of the displacement)
    assert abs(r.joint_relative_difference) <= ml.AGREEMENT_REL
