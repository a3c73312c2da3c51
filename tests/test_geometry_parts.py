"""Part meshes: watertight, volumes against closed forms, regions, contact sides facing each other,
determinism, cache keys, errors. Coarse sizes keep the default run fast."""
from __future__ import annotations

import math

import numpy as np
import pytest

from femcheck.errors import CaseError, FemcheckError
from geometry import MeshingError, build_part, cache
from geometry.case_params import with_params
from geometry.quality import is_watertight
from geometry.regions import facet_geometry, opposed_normal_angles_deg

CASE = "cases/haptic_6psu.toml"
#: coarse sizes (m) for the default test run
COARSE = {"guideway": 0.006, "proximal_link": 0.004, "spherical_joint": 0.0015, "universal_joint": 0.002, "platform": 0.006}

EXPECTED_REGIONS = {
    "guideway": {"lg_clamp", "lg_slider", "lg_load"},
    "proximal_link": {"prox_end_B", "prox_end_C", "prox_load"},
    "spherical_joint": {"sj_ball_contact", "sj_seat_contact", "sj_ball_link", "sj_seat_mount", "sj_load"},
    "universal_joint": {"uj_a1_pin_contact", "uj_a1_bore_contact", "uj_a2_pin_contact", "uj_a2_bore_contact", "uj_hub",
                        "uj_platform_mount", "uj_link_mount", "uj_load"},
    "platform": {f"pf_mount_{i}" for i in range(6)} | {"pf_handle", "pf_load"},
}


pytestmark = pytest.mark.usefixtures("isolated_mesh_cache")


@pytest.fixture(scope="module")
def coarse(case):
    return {part: build_part(case, part, size) for part, size in COARSE.items()}


@pytest.fixture(scope="module")
def socket(case):
    c = with_params(case, **{"solid.spherical_joint.seat": "socket"})
    return build_part(c, "spherical_joint", COARSE["spherical_joint"])


@pytest.mark.parametrize("part", list(COARSE))
def test_every_body_is_watertight_and_positively_oriented(coarse, part):
    m = coarse[part]
    for i, b in enumerate(m.bodies):
        assert is_watertight(m.tets[m.body_of_tet == i]), f"{part}/{b.name} is not a closed manifold"
    assert (m.tet_volumes() > 0).all()


def test_socket_seat_is_watertight(socket):
    for i, b in enumerate(socket.bodies):
        assert is_watertight(socket.tets[socket.body_of_tet == i]), b.name


@pytest.mark.parametrize("part", ["guideway", "proximal_link", "universal_joint", "platform"])
def test_volume_within_1pct_of_analytic_at_default_size(case, part):
    m = build_part(case, part)
    for name, q in m.quality["bodies"].items():
        # issue 4 acceptance: 1 % of the analytic volume at the default size
        assert abs(q["volume_rel_error"]) < 0.01, (name, q["volume_rel_error"])


@pytest.mark.parametrize("seat", ["flat", "socket"])
def test_spherical_joint_volume_within_1pct_at_default_size(case, seat):
    m = build_part(with_params(case, **{"solid.spherical_joint.seat": seat}), "spherical_joint")
    for name, q in m.quality["bodies"].items():
        assert abs(q["volume_rel_error"]) < 0.01, (name, q["volume_rel_error"])  # issue 4 acceptance


def test_spherical_joint_volume_within_1pct_at_coarse_size(coarse, socket):
    for m in (coarse["spherical_joint"], socket):
        for name, q in m.quality["bodies"].items():
            # the coarse mesh already meets the 1 % of the acceptance (inscribed polyhedra, polygons)
            assert abs(q["volume_rel_error"]) < 0.01, (name, q["volume_rel_error"])


def test_tube_volume_error_is_the_polygon_closed_form(coarse):
    m = coarse["proximal_link"]
    n = 48  # nodes around (minimum of structured.n_around; 2 pi r / size is smaller here)
    expected = math.sin(2 * math.pi / n) / (2 * math.pi / n) - 1.0  # area of the inscribed n-gon / circle - 1
    # structured nodes lie exactly on the circles; only round-off remains
    assert m.quality["bodies"]["link"]["volume_rel_error"] == pytest.approx(expected, abs=1e-9)


def test_box_volume_is_exact(coarse):
    # the bar is a box meshed without approximation: round-off only
    assert abs(coarse["guideway"].quality["bodies"]["guideway"]["volume_rel_error"]) < 1e-12


@pytest.mark.parametrize("part", list(COARSE))
def test_regions_present_and_non_empty(coarse, part):
    m = coarse[part]
    assert set(m.regions) == EXPECTED_REGIONS[part]
    for name, r in m.regions.items():
        assert len(r.nodes) > 0, name
        if r.kind != "load":
            assert len(r.facets) > 0, name
        if r.kind in ("coupling", "clamp", "load"):
            assert r.reference_point is not None and r.reference_point.shape == (3,), name
        # facet normals are unit vectors and match the facet geometry
        if len(r.facets):
            _, n, _ = facet_geometry(m.points, r.facets)
            assert np.allclose(r.normals, n, atol=1e-12)


def test_facet_normals_point_out_of_the_body(coarse):
    m = coarse["spherical_joint"]
    r = m.regions["sj_ball_link"]
    c, n, _ = facet_geometry(m.points, r.facets)
    # a sphere's outward normal is radial: facets of the icosphere-sized mesh lie within a few degrees
    assert (np.einsum("ij,ij->i", n, c / np.linalg.norm(c, axis=1)[:, None]) > math.cos(math.radians(10))).all()


def test_flat_seat_contact_sides_face_each_other(case, coarse):
    m = coarse["spherical_joint"]
    master, slave = m.contact_pairs()["sj"]
    ang = opposed_normal_angles_deg(m.points, master, slave)
    R, zone = case.spherical_joint.ball_radius_m, case.solid.spherical_joint.contact_zone_radius_m
    # sphere on plane: ball normals in the zone tilt up to asin(zone / R) from -z; +5 deg for the facet size
    assert ang.max() < math.degrees(math.asin(zone / R)) + 5.0
    # the ball touches the seat at one point: seat contact node at distance R from the centre (gap 0)
    gap = np.linalg.norm(m.points[slave.nodes], axis=1).min() - R
    assert abs(gap) < 1e-12  # exact placement, round-off only


def test_socket_contact_sides_face_each_other(case, socket):
    master, slave = socket.contact_pairs()["sj"]
    ang = opposed_normal_angles_deg(socket.points, master, slave)
    # conformal sphere in sphere: normals differ only by facet size (<= 5 deg) and nearest-facet pairing
    assert np.median(ang) < 5.0 and ang.max() < 10.0
    c = case.solid.spherical_joint.socket_clearance_m
    d = np.linalg.norm(socket.points[slave.nodes] - [0, 0, c], axis=1)
    R = case.spherical_joint.ball_radius_m
    # cup nodes lie on the socket sphere R + c (structured nodes are exact)
    assert np.allclose(d, R + c, atol=1e-12)


def test_universal_joint_contact_sides_face_each_other(case, coarse):
    m = coarse["universal_joint"]
    pairs = m.contact_pairs()
    assert set(pairs) == {"uj_a1", "uj_a2"}
    r = case.universal_joint.pin_radius_m
    c = case.solid.universal_joint.pin_clearance_m
    for name, (master, slave) in pairs.items():
        ang = opposed_normal_angles_deg(m.points, master, slave)
        # same angular sampling on pin and bore: the nearest facet is at most one step (360/48 deg) away
        assert ang.max() < 360.0 / 48, name
        # pin_position = "bottom": pin bottom line lies on the bore bottom (zero gap), elsewhere gap <= 2 c
        zmin_pin = m.points[master.nodes][:, 2].min()
        zmin_bore = m.points[slave.nodes][:, 2].min()
        assert zmin_pin == pytest.approx(zmin_bore, abs=1e-12)
        assert zmin_bore == pytest.approx(-(r + c), abs=1e-12)


@pytest.mark.parametrize("part", ["guideway", "proximal_link", "universal_joint", "platform"])
def test_two_runs_give_identical_meshes_without_cache(case, part):
    a = build_part(case, part, COARSE[part], use_cache=False)
    b = build_part(case, part, COARSE[part], use_cache=False)
    assert np.array_equal(a.points, b.points) and np.array_equal(a.tets, b.tets)
    assert a.cache_key == b.cache_key
    for k in a.regions:
        assert np.array_equal(a.regions[k].facets, b.regions[k].facets)


def test_two_runs_give_identical_spherical_joint_through_the_cache(case, coarse):
    b = build_part(case, "spherical_joint", COARSE["spherical_joint"])
    a = coarse["spherical_joint"]
    assert a.cache_key == b.cache_key
    assert np.array_equal(a.points, b.points) and np.array_equal(a.tets, b.tets)


def _assert_identical(a, b):
    assert a.cache_key == b.cache_key
    for name in ("points", "tets", "body_of_tet"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape and np.array_equal(x, y), name  # bit-identical, no tolerance
    assert a.bodies == b.bodies and list(a.regions) == list(b.regions)
    for k in a.regions:
        ra, rb = a.regions[k], b.regions[k]
        assert np.array_equal(ra.facets, rb.facets) and np.array_equal(ra.nodes, rb.nodes), k
        assert np.array_equal(ra.normals, rb.normals), k


@pytest.mark.parametrize("link_direction", [(0.0, 0.0, 1.0), (0.6, 0.0, 0.8)])
def test_two_cold_spherical_joint_builds_are_bit_identical(case, link_direction):
    # issue acceptance: two runs produce identical meshes without the cache (structured cubed-sphere ball;
    # the former fTetWild ball differed between runs, docs/fe_solver.md)
    from geometry import spherical_joint
    a = spherical_joint.build(case, COARSE["spherical_joint"], link_direction=link_direction, use_cache=False)
    b = spherical_joint.build(case, COARSE["spherical_joint"], link_direction=link_direction, use_cache=False)
    _assert_identical(a, b)
    assert a.parameters["refinement"] == "structured"


def test_changing_a_spherical_joint_parameter_changes_mesh_and_cache_key(case, coarse):
    a = coarse["spherical_joint"]
    R2 = 0.004
    b = build_part(with_params(case, **{"spherical_joint.ball_radius_m": R2}), "spherical_joint", COARSE["spherical_joint"], use_cache=False)
    assert a.cache_key != b.cache_key
    ball = b.body_index("ball")
    from geometry.regions import boundary_facets
    surf = np.unique(boundary_facets(b.tets[b.body_of_tet == ball]))
    assert np.allclose(np.linalg.norm(b.points[surf], axis=1), R2, rtol=1e-12, atol=0)  # nodes on the new sphere
    c = build_part(with_params(case, **{"solid.spherical_joint.contact_zone_radius_m": 0.0008}), "spherical_joint",
                   COARSE["spherical_joint"], use_cache=False)
    assert c.cache_key != a.cache_key
    assert c.points.shape != a.points.shape or not np.array_equal(c.points, a.points)


def test_changing_a_parameter_changes_mesh_and_cache_key(case, coarse):
    a = coarse["universal_joint"]
    c2 = with_params(case, **{"universal_joint.pin_radius_m": 0.0012})
    b = build_part(c2, "universal_joint", COARSE["universal_joint"])
    assert a.cache_key != b.cache_key
    pin = b.regions["uj_a1_pin_contact"]
    # the pin surface follows the parameter: nodes at radius 1.2 mm from the pin axis (shifted by the clearance)
    cl = case.solid.universal_joint.pin_clearance_m
    rad = np.hypot(b.points[pin.nodes, 1], b.points[pin.nodes, 2] + cl)
    assert np.allclose(rad, 0.0012, atol=1e-12)
    assert a.points.shape != b.points.shape or not np.allclose(a.points, b.points)
    # a solid-only parameter and the size change the key too
    c3 = with_params(case, **{"solid.universal_joint.pin_clearance_m": 2e-5})
    assert build_part(c3, "universal_joint", COARSE["universal_joint"]).cache_key != a.cache_key
    assert build_part(case, "universal_joint", 0.0025).cache_key != a.cache_key


def test_code_version_is_part_of_the_cache_key(monkeypatch):
    k1 = cache.cache_key("guideway", {"a": 1})
    monkeypatch.setattr(cache, "code_version", lambda: "other")
    assert cache.cache_key("guideway", {"a": 1}) != k1


def test_flat_and_socket_seats_differ(coarse, socket):
    a = coarse["spherical_joint"]
    assert a.cache_key != socket.cache_key
    assert a.parameters["seat"] == "flat" and socket.parameters["seat"] == "socket"
    assert a.bodies[1].analytic_volume_m3 != socket.bodies[1].analytic_volume_m3


def test_bad_parameters_give_clear_errors(case):
    c = with_params(case, **{"universal_joint.pin_span_m": 0.008})
    with pytest.raises(MeshingError, match=r"meshing universal_joint failed \(.*pin_span_m=0.008.*\): pin_span_m - contact_length_m"):
        build_part(c, "universal_joint", 0.002, use_cache=False)
    c = with_params(case, **{"solid.spherical_joint.seat": "socket", "solid.spherical_joint.socket_depth_m": 0.005})
    with pytest.raises(MeshingError, match="socket_depth_m = 0.005 exceeds the socket radius"):
        build_part(c, "spherical_joint", 0.0015, use_cache=False)
    with pytest.raises(CaseError, match=r"solid\.universal_joint\.pin_clearance_m: = -1e-05 m; expected >= 0"):
        with_params(case, **{"solid.universal_joint.pin_clearance_m": -1e-5})
    with pytest.raises(CaseError, match=r"solid\.spherical_joint\.seat: got 'cone'"):
        with_params(case, **{"solid.spherical_joint.seat": "cone"})
    with pytest.raises(MeshingError, match="unknown part"):
        build_part(case, "crank")
    with pytest.raises(MeshingError, match=r"size = -0.001 m; expected a positive edge length"):
        build_part(case, "guideway", -0.001)
    with pytest.raises(FemcheckError):
        build_part(case, "platform", 0.05)  # coarser than the mount patches


def test_to_skfem_maps_regions_to_boundary_facets(coarse):
    m = coarse["universal_joint"]
    sk = m.to_skfem()
    assert sk.t.shape[1] == len(m.tets) and sk.p.shape[1] == len(m.points)
    for name, r in m.regions.items():
        if not len(r.facets):
            continue
        idx = sk.boundaries[name]
        assert np.array_equal(np.sort(np.sort(sk.facets[:, idx].T, axis=1), axis=0), np.sort(np.sort(r.facets, axis=1), axis=0))
        assert np.isin(idx, sk.boundary_facets()).all()  # contact/coupling facets are boundary facets
    assert set(sk.subdomains) == {b.name for b in m.bodies}


def test_mount_and_clamp_areas_match_closed_forms(case, coarse):
    uj, so = case.universal_joint, case.solid.universal_joint
    w = 2 * (uj.pin_radius_m + so.pin_clearance_m + so.yoke_wall_m)
    for name in ("uj_platform_mount", "uj_link_mount"):
        _, _, a = facet_geometry(coarse["universal_joint"].points, coarse["universal_joint"].regions[name].facets)
        # two arm faces of w x l each, planar and meshed exactly: round-off only
        assert a.sum() == pytest.approx(2 * w * uj.contact_length_m, rel=1e-12)
    g = case.guideway
    _, _, a = facet_geometry(coarse["guideway"].points, coarse["guideway"].regions["lg_clamp"].facets)
    assert a.sum() == pytest.approx(g.width_radial_m * g.depth_tangential_m, rel=1e-12)  # exact rectangle
