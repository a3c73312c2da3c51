"""Joint contact FE: the device load the joints carry, the closed-form joint laws they are
compared with, the named geometry errors, the joint table, and (slow) the condensed contact FE itself."""
from __future__ import annotations

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest

from femcheck.fe_device import joint_check as jc
from femcheck.fe_device import joint_fe as jf


def test_leg_forces_carry_the_tcp_wrench(case):
    """Released-joint statics: Σ f_i [u_i; (C_i − tcp) × u_i] = W for every direction and level."""
    from femcheck.fe_device.loads import direction_unit
    from femcheck.kinematics.psu6 import leg_geometry, test_points
    f = jc.leg_forces(case, "P3")
    legs = leg_geometry(case, test_points(case)[[3]])
    u, C, tcp = legs.u[0], legs.C[0], legs.tcp[0]
    J = np.vstack([u.T, np.cross(C - tcp, u).T])
    L = case.loads
    for d, name in enumerate(L.directions):
        for k, P in enumerate((L.detailed_preload_N, L.detailed_preload_N + L.detailed_test_N)):
            W = np.r_[P * direction_unit(name), 0, 0, 0]
            # a 6 x 6 solve: round-off of the well-conditioned leg Jacobian
            assert np.allclose(J @ f[d, k], W, atol=1e-9 * P)
    F5, F20 = jc.joint_loads(case, "P0")
    # statics is linear in the load: the two eq. 1 levels keep the ratio of the TCP loads (20 N / 5 N)
    assert F20 / F5 == pytest.approx((L.detailed_preload_N + L.detailed_test_N) / L.detailed_preload_N, rel=1e-12)
    with pytest.raises(Exception, match="P9"):
        jc.leg_forces(case, "P9")


def test_analytical_compliance_is_the_closed_form_laws(case):
    """Spherical axial = Hertz secant of eq. 1 (Johnson 4.23); universal axial = c_UC + c_UB (seed 000 eqs. 36–41)."""
    from femcheck.chain import device_parameters
    from femcheck.fe_device.joint_friction import joint_friction
    fr = joint_friction(case)
    C = jf.analytical_compliance(case, "spherical", (5.0, 20.0))
    d = (3.0 * np.array([5.0, 20.0]) / (4.0 * fr.E_star_Pa * math.sqrt(fr.R_star_m))) ** (2.0 / 3.0)
    assert C[2, 2] == pytest.approx((d[1] - d[0]) / 15.0, rel=1e-12)  # same closed form, round-off
    # Hertz is stiffening: the secant of the increment is below the secant from zero at the preload
    assert C[2, 2] < d[0] / 5.0
    p = device_parameters(case)
    U = jf.analytical_compliance(case, "universal", (5.0, 20.0))
    assert U[2, 2] == pytest.approx(float(np.squeeze(p.c_uc)) + float(np.squeeze(p.c_ub)), rel=1e-12)
    assert U[0, 0] == U[1, 1] == pytest.approx(float(np.squeeze(p.c_uc)), rel=1e-12)
    assert U[5, 5] == 0.0  # the U-joint spin is tied in the analytical model


def _pair(g0):
    g0 = np.asarray(g0, float)
    return SimpleNamespace(g0=g0, n_points=g0.size)


def test_named_geometry_errors():
    """Interpenetration beyond the clearance and an unresolved pin clearance are named errors."""
    h = 1e-4
    jf._check_gaps("universal", [_pair([0.0, 1e-6, 2e-5])], 1e-5, h)  # chord noise 0: fine
    with pytest.raises(jf.JointGeometryError, match="interpenetration"):
        jf._check_gaps("universal", [_pair([-3e-5, 0.0])], 1e-5, h)
    with pytest.raises(jf.JointGeometryError, match="not resolved"):
        jf._check_gaps("universal", [_pair([-6e-6, 0.0])], 1e-5, h)
    with pytest.raises(jf.JointGeometryError, match="interpenetration"):
        jf._check_gaps("spherical", [_pair([-1e-6, 0.0])], 0.0, h)
    jf._check_gaps("spherical", [_pair([-1e-8, 0.0])], 0.0, h)  # below 0.1 % of the contact edge: facet noise


def test_candidate_band_keeps_both_contact_lines():
    """Pin in bore: points near the first-contact line (g ≈ 0) and the opposite line (g ≈ 2c) are kept."""
    c = 1e-5
    theta = np.linspace(0, 2 * np.pi, 73)
    p = _pair(c * (1 - np.cos(theta)))
    keep = jf._candidates(p, c)
    ang = np.minimum(np.abs(np.angle(np.exp(1j * theta))), np.pi - np.abs(np.angle(np.exp(1j * theta))))
    assert np.all(keep[ang < jf.CANDIDATE_ANGLE_RAD - 1e-9])
    assert not np.any(keep[ang > jf.CANDIDATE_ANGLE_RAD + 1e-9])
    assert jf._candidates(p, 0.0).all()  # no clearance (ball in seat): the whole contact region


def test_joint_table_rows_flag_and_csv():
    """Rows per (joint, component); laws off by > 10 % are flagged with a named better law; CSV round trip."""
    fe = np.diag([1.0, 1.0, 1.2, 1.0, 1.0, np.inf])
    an = np.diag([1.0, 1.0, 1.0, 1.05, 1.0, 1.0])
    res = {"joint": "universal", "fe_component_compliance": jc._json_matrix(np.diag(fe)[None])[0],
           "analytical_compliance": jc._json_matrix(an)}
    rows = {r["component"]: r for r in jc.joint_table_rows([res])}
    assert rows["axial"]["error_pct"] == pytest.approx(20.0)
    assert rows["axial"]["off_by_more_than_10pct"] and "conformal" in rows["axial"]["better_law"]
    assert not rows["tilt"]["off_by_more_than_10pct"] and rows["tilt"]["better_law"] == ""
    assert rows["spin"]["error_pct"] is None  # FE mechanism (inf): no percentage
    text = jc.write_joint_table_csv(list(rows.values()))
    assert text.splitlines()[0].startswith("joint,component,fe_compliance")
    assert len(text.splitlines()) == 5
    e = jf.error_pct(fe, an)
    assert e["u_z"] == pytest.approx(20.0) and e["theta_z"] is None


def test_cli_rejects_bad_joint(tmp_path):
    from femcheck.cli import main
    assert main(["check-joints", "cases/haptic_6psu.toml", "--joint", "elbow"]) == 2


def _check_joint_coarse(tmp_path, joint):
    """The one row of ``femcheck check-joints --joint <joint> --mesh coarse --json`` on the reference case, which
    must exit 0 and carry the contract keys."""
    from femcheck.cli import main
    out = tmp_path / f"{joint}.json"
    assert main(["check-joints", "cases/haptic_6psu.toml", "--joint", joint, "--mesh", "coarse",
                 "--json", str(out)]) == 0
    (r,) = json.loads(out.read_text())
    for key in ("converged", "dofs", "iterations", "seconds", "fe_compliance", "analytical_compliance", "error_pct"):
        assert key in r
    return r


@pytest.mark.slow
def test_spherical_joint_contact_fe_coarse(case, tmp_path):
    """Condensed ball-in-seat contact FE: converges, and its eq. 1 axial secant is Hertz within 25 %.

    The FE contains the seat's bulk compression and the ball between contact and cap besides the Hertz
    approach of two half-spaces (softer), and the coarse mesh resolves the patch with few points; 25 %
    bounds both (measured −7 % at coarse, docs/verify.md)."""
    r = _check_joint_coarse(tmp_path, "spherical")
    assert r["converged"] and r["dofs"] > 10_000 and r["iterations"] > 0
    assert np.shape(r["fe_compliance"]) == (6, 6) and np.shape(r["analytical_compliance"]) == (6, 6)
    assert abs(r["error_pct"]["u_z"]) < 25.0
    assert r["retained_dofs"] < r["free_dofs"] / 10  # the condensation is what makes it fast


def test_joint_law_adjustments_scale_the_joint_elements(case):
    """The FE-measured axial law enters the extended model as the sp/uj element factor FE / closed form,
    and changes the TCP compliance in the direction of the factor (softer joint -> softer device)."""
    from femcheck.chain import ELEMENTS, evaluate
    from femcheck.kinematics.psu6 import test_points
    an = jf.analytical_compliance(case, "spherical")
    res = {"joint": "spherical", "fe_component_compliance": [None, None, 1.5 * an[2, 2], None, None, None],
           "analytical_compliance": jc._json_matrix(an)}
    adj = jc.joint_law_adjustments([res])
    assert adj.element_scale[:, ELEMENTS.index("sp")] == pytest.approx(1.5)  # exactly the ratio given
    assert np.all(adj.element_scale[:, ELEMENTS.index("uj")] == 1.0)
    poses = test_points(case)[:1]
    base = evaluate(case, poses, model="detailed", backend="numpy")
    soft = evaluate(case, poses, model="detailed", adjust=adj, backend="numpy")
    assert np.trace(soft.S[0][:3, :3]) > np.trace(base.S[0][:3, :3])


def test_joint_table_html_names_flagged_laws():
    an = np.diag([1.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    res = {"joint": "spherical", "fe_component_compliance": [1.0, 1.0, 1.3, 1.0, 1.0, 1.0],
           "analytical_compliance": jc._json_matrix(an)}
    text = jc.joint_table_html(jc.joint_table_rows([res]))
    assert "seat-bulk" in text and text.count("within 10 %") == 3  # axial flagged, three others within


@pytest.fixture(scope="module")
def spherical_coarse(case):
    """The ball-in-seat contact FE on a cheap graded mesh (patch edge a / 2, bulk 2 mm; the coarse level
    is a / 3 at 1 mm, ≈ 95 k DOFs, for the slow tests), built once (mesh, assembly, condensation)."""
    from femcheck.fe_device.joint_friction import joint_friction
    loads = jc.joint_loads(case, "P0")
    a = float(joint_friction(case).contact_radius(max(loads)))
    model = jf.build_joint(case, "spherical", "coarse", max_load_N=max(loads),
                           mesh_options={"contact_size_m": a / 2, "contact_zone_radius_m": 1.3 * a, "grading": 0.5})
    an = jf.analytical_compliance(case, "spherical", loads)
    # penetration accepted: 1e-3 of the analytical approach at the preload (as check_joint)
    tol = 1e-3 * float(an[2, 2]) * min(loads)
    return model, loads, an, tol


def test_spherical_contact_fe_converges_symmetric_positive_definite(spherical_coarse):
    """Converged (true residual, no stabilising-spring force), reciprocal (Maxwell–Betti) and positive
    definite 6 x 6 tangent; eq. 1 axial secant Hertz within 25 % (seat bulk and a coarse patch: measured
    −4 %, docs/verify.md)."""
    model, loads, an, tol = spherical_coarse
    r = jf.solve_joint(model, loads, -1.0, penetration_tol=tol)
    assert r.residual_rel < 1e-8  # rtol 1e-9 of the solver on ‖f‖ = F_20
    assert r.stabilization_force_share < 1e-6
    K = r.tangent_stiffness
    assert np.allclose(K, K.T, rtol=0, atol=1e-12 * np.abs(K).max())
    # positive definite: the Cholesky of the unit-scaled stiffness exists (no contact mechanism)
    d = 1.0 / np.sqrt(np.diag(K))
    np.linalg.cholesky(K * np.outer(d, d))
    assert abs(r.secant_axial_m_per_N - an[2, 2]) / an[2, 2] < 0.25
    assert r.iterations > 0 and r.factorizations > 0


def test_spherical_joint_pulled_out_is_a_convergence_error(spherical_coarse):
    """A load that pulls the ball out of its seat has no equilibrium: ConvergenceError with the residual
    history, never numbers."""
    from femcheck.errors import ConvergenceError
    model, loads, an, tol = spherical_coarse
    with pytest.raises(ConvergenceError) as exc:
        jf.solve_joint(model, loads, +1.0, penetration_tol=tol)
    assert exc.value.residual_history


@pytest.mark.slow
def test_universal_joint_contact_fe_converges_coarse(case, tmp_path):
    """The cross floating in its 2c clearance seats and converges (it chattered before); the
    6 x 6 tangent is symmetric and positive definite; the JSON carries the contract keys. Slow since the
    graded coarse level (238 k DOFs: about 40 s of CPU, 2–3 min wall on the loaded machine)."""
    r = _check_joint_coarse(tmp_path, "universal")
    assert r["converged"] and r["iterations"] > 0 and r["factorizations"] > 0
    assert r["stabilization_force_share"] < 1e-6 and r["residual_rel"] < 1e-8
    K = np.array(r["fe_tangent_stiffness"], float)
    d = 1.0 / np.sqrt(np.diag(K))
    np.linalg.cholesky(K * np.outer(d, d))
    C = np.array(r["fe_compliance"], float)
    assert np.allclose(C, C.T, rtol=0, atol=1e-12 * np.abs(C).max())
    # the link pushes the cross across the 2c clearance before the pins bear: the axial displacement at
    # the preload exceeds 2c (the secant excludes it)
    assert r["closed_points"] > 0


def test_joint_table_section_for_the_verify_report():
    """The joint table as a verify-report Section: one row per (joint, component), flagged laws named."""
    an = np.diag([1.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    res = {"joint": "universal", "fe_component_compliance": [1.0, 1.0, 1.3, 1.0, 1.0, None],
           "analytical_compliance": jc._json_matrix(an)}
    sec = jc.joint_table_section(jc.joint_table_rows([res]))
    assert len(sec.rows) == 4 and "conformal" in sec.note
    from femcheck.verify.render import render_markdown
    assert "Joint table" in render_markdown("t", "", [sec])


def test_graded_joint_levels_scale_the_contact_patch_on_the_hertz_radius(case):
    """The spherical levels put a / 3, a / 4.5, a / 6 elements in the Hertz patch (a at the largest joint
    load) and keep the bulk size; the coarse mesh itself has that edge in the patch and the bulk edge away
    from it (measured on the mesh: facet edges of the seat top and the ball surface)."""
    from femcheck.fe_device.joint_friction import joint_friction
    from femcheck.fe_device.mesh_levels import joint_mesh_sizes
    from geometry import spherical_joint
    from geometry.regions import boundary_facets, facet_geometry
    F20 = max(jc.joint_loads(case, "P0"))
    a = float(joint_friction(case).contact_radius(F20))
    levels = {lv: joint_mesh_sizes(case, "spherical", lv, F20) for lv in ("coarse", "default", "fine")}
    assert [a / levels[lv].contact_m for lv in levels] == pytest.approx([3.0, 4.5, 6.0], rel=1e-12)  # definition
    assert len({ms.bulk_m for ms in levels.values()}) == 1  # the bulk is the same at every level
    ms = levels["coarse"]
    pm = spherical_joint.build(case, ms.bulk_m, contact_size_m=ms.contact_m, contact_zone_radius_m=ms.zone_m,
                               grading=ms.grading)

    def edges(f):
        return np.linalg.norm(pm.points[f] - pm.points[np.roll(f, 1, axis=1)], axis=2).mean(axis=1)

    for name in ("sj_seat_contact", "sj_ball_contact"):
        f = pm.regions[name].facets
        c, _, _ = facet_geometry(pm.points, f)
        patch = np.hypot(c[:, 0], c[:, 1]) < a
        e = edges(f[patch])
        # longest-edge bisection to a mean tet edge ≤ the target leaves surface edges 0.7–1.2 x the target
        assert 0.6 * ms.contact_m < e.mean() < 1.25 * ms.contact_m, (name, e.mean() / ms.contact_m)
        assert patch.sum() >= 40  # the patch is resolved by tens of facets per side
    # away from the contact the bulk edge is kept: seat top beyond 4 mm > 5 x the patch edge; ball top half
    # (the cubed sphere's surface edge, 0.35 x the bulk size) > 2.5 x
    seat = boundary_facets(pm.tets[pm.body_of_tet == [b.name for b in pm.bodies].index("seat")])
    c, n, _ = facet_geometry(pm.points, seat)
    far = (np.hypot(c[:, 0], c[:, 1]) > 0.004) & (n[:, 2] > 0.99)
    assert far.sum() > 0 and edges(seat[far]).mean() > 5 * ms.contact_m
    ball = boundary_facets(pm.tets[pm.body_of_tet == [b.name for b in pm.bodies].index("ball")])
    cb, _, _ = facet_geometry(pm.points, ball)
    assert edges(ball[cb[:, 2] > 0]).mean() > 2.5 * ms.contact_m


def test_exact_sphere_gap_removes_the_facet_sagitta(case):
    """Ball in a flat seat: the initial gap of a seat point at radius r is |x| − R = sqrt(R² + r²) − R
    exactly (≈ r² / (2 R)), whatever the ball's facets (round-off)."""
    R = float(case.spherical_joint.ball_radius_m)
    r = np.linspace(0.0, 5e-4, 11)
    pts = np.column_stack([r, np.zeros_like(r), np.full_like(r, -R)])
    import dataclasses as dc

    @dc.dataclass(frozen=True)
    class Pair:  # the two fields of a contact pair that the function reads and replaces
        points: np.ndarray
        g0: np.ndarray
    out = jf._exact_sphere_gap(case, Pair(pts, np.full(r.size, -1.0)))  # facet gaps: anything
    assert out.g0 == pytest.approx(np.sqrt(R**2 + r**2) - R, abs=1e-15)
    # the Hertz parabola r² / (2 R) up to its next term, −r⁴ / (8 R³): 0.5 % at r = 0.5 mm
    assert out.g0 == pytest.approx(r**2 / (2 * R), rel=1e-2, abs=1e-15)


@pytest.mark.slow
def test_spherical_joint_mesh_convergence_within_3_percent(case):
    """Issue 14 target: every compliance component of the ball-in-seat contact FE within 3 % over the
    coarse, default and fine levels (patch edge a / 3, a / 4.5, a / 6; max − min over the fine value).
    Measured spread ≤ 1.5 % (docs/verify.md); the bulk is the same at every level, so this is the
    convergence of the contact zone (≈ 6 min on the shared 2-core machine)."""
    comps = np.array([jc.check_joint(case, "spherical", lv, "P0")["fe_component_compliance"]
                      for lv in ("coarse", "default", "fine")], float)
    spread = 100.0 * (comps.max(axis=0) - comps.min(axis=0)) / np.abs(comps[-1])
    assert np.all(spread <= 3.0), dict(zip(jf.COMPONENTS, spread.round(2)))


def test_universal_levels_crowd_the_nodes_at_the_loaded_lines(case):
    """The universal levels warp the angles around pins and bores (φ + (A/2) sin 2φ): measured on the
    coarse mesh, the bore nodes at the bottom/top lines are 1 − A of the uniform spacing apart and
    1 + A at the sides (the nodes lie on the exact circle; tolerance: the uniform φ grid is discrete)."""
    from femcheck.fe_device.mesh_levels import UNIVERSAL_WARP, joint_mesh_sizes
    ms = joint_mesh_sizes(case, "universal", "coarse")
    pm = _universal_level_mesh(case, ms)
    r = float(case.universal_joint.pin_radius_m) + float(case.solid.universal_joint.pin_clearance_m)
    f = pm.regions["uj_a2_bore_contact"].facets  # link bores: axis y, section (x, z)
    nodes = pm.points[np.unique(f)]
    ang = np.unique(np.round(np.arctan2(nodes[:, 2], nodes[:, 0]), 9))
    assert np.allclose(np.hypot(nodes[:, 0], nodes[:, 2]), r, rtol=1e-9)  # on the bore circle
    gaps = np.diff(np.r_[ang, ang[0] + 2 * np.pi])
    mid = 0.5 * (ang + np.r_[ang[1:], ang[0] + 2 * np.pi])
    uniform = 2 * np.pi / ang.size
    A = UNIVERSAL_WARP["coarse"]
    at_line = gaps[np.abs(np.abs(np.sin(mid)) - 1) < 0.02]
    at_side = gaps[np.abs(np.sin(mid)) < 0.2]
    assert at_line.min() / uniform == pytest.approx(1 - A, rel=0.05)
    assert at_side.max() / uniform == pytest.approx(1 + A, rel=0.05)
    assert at_line.max() < uniform < at_side.min()  # finer than uniform at the lines, coarser at the sides


def _universal_level_mesh(case, ms):
    from geometry import universal_joint
    return universal_joint.build(case, ms.bulk_m, contact_warp=ms.contact_warp, contact_size_m=ms.surface_m,
                                 axial_size_m=ms.axial_m, hub_levels=ms.hub_levels)


def _pin_a1_axial_levels(pm):
    i = [b.name for b in pm.bodies].index("pin_a1")
    return np.unique(np.round(pm.points[np.unique(pm.tets[pm.body_of_tet == i])][:, 0], 12))


def _hub_tie_half_length(pm):
    """Largest |x| of the uj_hub tie nodes on pin a1's surface (pin a1 lies along x)."""
    x = pm.points[pm.regions["uj_hub"].nodes]
    return float(np.abs(x[np.abs(x[:, 1]) < 1e-9, 0]).max())


def test_universal_levels_refine_the_bulk_and_tie_the_hub_over_its_length(case):
    """The universal levels refine the bulk too: the element length along the pins in the bores and
    through the yoke arms is 2, 1.4, 1 x the case size (measured on the meshes: pin levels inside a bore,
    arm layers), and the rigid hub ties exactly hub_half_length_m at every level (the hub ends are
    element levels). Without that, the 2 mm mesh (levels at ±1.8 mm) tied 1.8 mm only and the joint
    came out 6–7 % softer than at 1 mm (docs/verify.md)."""
    from femcheck.fe_device.mesh_levels import joint_mesh_sizes
    from geometry import universal_joint
    levels = {lv: joint_mesh_sizes(case, "universal", lv) for lv in ("coarse", "default", "fine")}
    size = float(case.solid.mesh.universal_joint_size_m)
    assert [levels[lv].axial_m / size for lv in levels] == pytest.approx([2.0, 1.4, 1.0], rel=1e-12)  # definition
    hub = float(case.solid.universal_joint.hub_half_length_m)
    Lu, l = float(case.universal_joint.pin_span_m), float(case.universal_joint.contact_length_m)
    for lv in ("coarse", "fine"):
        ms = levels[lv]
        pm = _universal_level_mesh(case, ms)
        x = _pin_a1_axial_levels(pm)
        in_bore = x[(x >= Lu / 2 - l / 2 - 1e-12) & (x <= Lu / 2 + l / 2 + 1e-12)]
        # bore of length l in whole elements of at most axial_m (round-off of the level coordinates)
        assert in_bore.size - 1 == math.ceil(l / ms.axial_m - 1e-9), (lv, in_bore)
        assert np.diff(in_bore).max() <= ms.axial_m * (1 + 1e-9)
        assert _hub_tie_half_length(pm) == pytest.approx(hub, abs=1e-12)  # exact: hub ends are levels
    # the mesh before: hub ends not levels, the 2 mm pin levels fall at ±1.8 mm and the tie is short
    old = universal_joint.build(case, levels["coarse"].bulk_m, contact_warp=levels["coarse"].contact_warp,
                                contact_size_m=levels["coarse"].surface_m)
    assert _hub_tie_half_length(old) < 0.95 * hub


@pytest.mark.slow
def test_universal_joint_mesh_convergence_within_3_percent(case):
    """Issue 14 target for the pins in their bores: every compliance component within 3 % over the graded
    coarse, default and fine levels, which refine the contact zone (nodes crowded at the loaded lines,
    warp 0.5 / 0.75 / 0.875) and the bulk (element length along the pins and through the yoke arms 2, 1.4,
    1 mm; hub ends exact at every level). Measured spread ≤ 2.72 % (θ_x, θ_z; docs/verify.md; the three
    check-joints runs took 13.6 min wall at load average 7–8; this test 6.0 min, 6.8 GB peak)."""
    from femcheck.fe_device.mesh_levels import joint_mesh_sizes
    axial = [joint_mesh_sizes(case, "universal", lv).axial_m for lv in ("coarse", "default", "fine")]
    assert axial[0] > axial[1] > axial[2]  # the levels refine the bulk, not only the contact zone
    comps = np.array([jc.check_joint(case, "universal", lv, "P0")["fe_component_compliance"]
                      for lv in ("coarse", "default", "fine")], float)
    spread = 100.0 * (comps.max(axis=0) - comps.min(axis=0)) / np.abs(comps[-1])
    assert np.all(spread <= 3.0), dict(zip(jf.COMPONENTS, spread.round(2)))


def test_check_joints_verdict_line_names_the_laws_off_by_more_than_10pct():
    """The last line of check-joints: every law within 10 %, or the ones that are not, with their error."""
    an = np.diag([1.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    ok = {"joint": "spherical", "fe_component_compliance": [1.0, 1.0, 1.05, 1.0, 1.0, 1.0],
          "analytical_compliance": jc._json_matrix(an)}
    off = {"joint": "universal", "fe_component_compliance": [1.0, 1.0, 1.3, 1.0, 1.0, None],
           "analytical_compliance": jc._json_matrix(an)}
    assert jc.verdict_line(jc.joint_table_rows([ok])).startswith("verdict: every closed-form joint law within 10 %")
    line = jc.verdict_line(jc.joint_table_rows([ok, off]))
    # axial of the universal joint is 30 % off; its free spin (None) has no percentage and is not counted
    assert "verdict: 1 closed-form" in line and "7 joint-table laws" in line and "universal axial (+30.0 %)" in line, line
    # the ETA weights: build then solve per joint, the universal joint the heavier
    w = jc.progress_weights(("spherical", "universal"))
    assert len(w) == 4 and w[2] + w[3] > w[0] + w[1]


def test_candidate_band_widens_only_when_the_contact_leaves_it(case, monkeypatch):
    """The U joint's solve is tried on band 0, then the wider bands in turn, and stops at the first whose contact stays
    inside; past the widest, one ConvergenceError names the joint and the bands (not the band error of one); the ball
    keeps its one Hertz band. A wider angle keeps a superset of the points."""
    from femcheck.errors import ConvergenceError
    from femcheck.fe_device import joint_models as jm
    monkeypatch.setattr(jm, "condensed_joint", lambda case, joint, mesh, load, band: band)
    tried = []

    def solve_from(good):
        def solve(band):
            tried.append(band)
            if band < good:
                raise jf.CandidateBandError("outside the band", [1.0], {"penetration_m": 1e-5})
            return band
        return solve
    assert jm.solve_widening(case, "universal", "coarse", 25.0, solve_from(1)) == 1 and tried == [0, 1]
    tried.clear()
    with pytest.raises(ConvergenceError, match="universal joint: the contact leaves every candidate band tried") as e:
        jm.solve_widening(case, "universal", "coarse", 25.0, solve_from(len(jf.CANDIDATE_BANDS)))
    assert not isinstance(e.value, jf.CandidateBandError) and tried == list(range(len(jf.CANDIDATE_BANDS)))
    tried.clear()
    with pytest.raises(ConvergenceError):
        jm.solve_widening(case, "spherical", "coarse", 25.0, solve_from(1))
    assert tried == [0]
    c = 1e-5
    theta = np.linspace(0, 2 * np.pi, 73)
    p = _pair(c * (1 - np.cos(theta)))
    narrow, wide = jf._candidates(p, c, "first"), jf._candidates(p, c, "first", 2 * jf.CANDIDATE_ANGLE_RAD)
    assert np.all(wide[narrow]) and wide.sum() > narrow.sum()


@pytest.mark.slow
def test_a_standard_thinner_pin_converges_with_a_wider_band(case):
    """The Ø1.5 mm dowel pin (radius x 0.75) bends into its bore outside the loaded lines' band; the widened band
    converges (3 min, 3.3 GB): the joint is softer than the Ø2 mm reference's at every ladder force (a thinner pin
    bends more; the approach includes the same 2c clearance), and grows with the load."""
    from femcheck.fe_device.joint_laws import measure_joint_law
    thin = case.with_params(**{"universal_joint.pin_radius_m": 0.75 * case.universal_joint.pin_radius_m})
    law = measure_joint_law(thin, "universal", "coarse", use_cache=False)
    ref = measure_joint_law(case, "universal", "coarse")
    assert np.all(law.approach_m > ref.approach_m) and np.all(np.diff(law.approach_m) > 0)
