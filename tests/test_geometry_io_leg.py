"""Mesh files, CLI, leg assembly, beam sections and quality measures of the geometry package."""
from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

from femcheck.cli import get_app
from geometry import build_part
from geometry.beam_mesh import guideway_beam, link_beam, rectangle_section, tube_section
from geometry.io import read_mesh, write_mesh
from geometry.quality import dihedral_angles_deg, is_watertight, radius_ratio

CASE = "cases/haptic_6psu.toml"


pytestmark = pytest.mark.usefixtures("isolated_mesh_cache")


@pytest.mark.parametrize("suffix", [".vtu", ".xdmf"])
def test_mesh_file_round_trip_keeps_regions(case, tmp_path, suffix):
    """Write and read back (VTU, and XDMF + HDF5 through h5py, a dependency): points, tets, bodies and every
    region's facets, nodes, kind, side and reference point come back exactly (both formats store float64)."""
    m = build_part(case, "universal_joint", 0.002)
    path = write_mesh(m, tmp_path / f"uj{suffix}")
    r = read_mesh(path)
    assert np.array_equal(r.points, m.points) and np.array_equal(r.tets, m.tets)
    assert np.array_equal(r.body_of_tet, m.body_of_tet)
    assert list(r.regions) == list(m.regions)
    for k, reg in m.regions.items():
        assert np.array_equal(r.regions[k].facets, reg.facets) and np.array_equal(r.regions[k].nodes, reg.nodes)
        assert r.regions[k].kind == reg.kind and r.regions[k].side == reg.side
        if reg.reference_point is not None:
            assert np.array_equal(r.regions[k].reference_point, reg.reference_point)
    if suffix == ".xdmf":
        assert path.with_suffix(".h5").is_file()   # the heavy data lives in the HDF5 file beside the XML


def test_cli_mesh_writes_vtu_sidecar_and_png(tmp_path):
    out, png = tmp_path / "uj.vtu", tmp_path / "uj.png"
    res = CliRunner().invoke(get_app(), ["mesh", CASE, "--part", "universal_joint", "--size", "0.002", "--out", str(out), "--png", str(png)])
    assert res.exit_code == 0, res.output
    assert out.is_file() and (tmp_path / "uj.vtu.json").is_file()
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "watertight=True" in res.output
    import json
    meta = json.loads((tmp_path / "uj.vtu.json").read_text())
    assert {r["name"] for r in meta["regions"]} >= {"uj_a1_pin_contact", "uj_a1_bore_contact", "uj_hub"}


def test_cli_bad_part_and_point_fail_cleanly(tmp_path):
    from femcheck.cli import main
    assert main(["mesh", CASE, "--part", "crank", "--out", str(tmp_path / "x.vtu")]) == 2
    assert main(["mesh", CASE, "--part", "leg", "--point", "P9", "--out", str(tmp_path / "x.vtu")]) == 2
    assert main(["mesh", CASE, "--part", "guideway", "--out", CASE]) == 2  # never overwrite the input


def test_leg_is_assembled_at_the_test_point(case):
    from femcheck.kinematics.psu6 import leg_geometry, test_points
    legs = leg_geometry(case, test_points(case)[3:4])
    chain = 2
    m = build_part(case, "leg", 0.0015, point="P3", chain=chain)
    A, B, C, u = legs.A[chain], legs.B[0, chain], legs.C[0, chain], legs.u[0, chain]
    # couplings carry the points of the analytical model (exact rigid transforms: round-off only)
    assert np.allclose(m.regions["lg_clamp"].reference_point, A, atol=1e-12)
    assert np.allclose(m.regions["sj_ball_link"].reference_point, B, atol=1e-12)
    assert np.allclose(m.regions["sj_seat_mount"].reference_point, B, atol=1e-12)
    # ball nodes on the sphere about B (snapped: round-off only)
    ball = m.body_index("ball")
    bn = np.unique(m.tets[m.body_of_tet == ball])
    d = np.linalg.norm(m.points[bn] - B, axis=1)
    assert d.max() == pytest.approx(case.spherical_joint.ball_radius_m, rel=1e-12)
    # the cross centre is at C shifted by the clearance toward B (pin_position = "bottom")
    cl = case.solid.universal_joint.pin_clearance_m
    assert np.allclose(m.regions["uj_hub"].reference_point, C - cl * u, atol=1e-12)
    # the tube spans from the ball surface to the link-yoke mount, along u
    e0, e1 = m.regions["prox_end_B"].reference_point, m.regions["prox_end_C"].reference_point
    assert np.allclose((e1 - e0) / np.linalg.norm(e1 - e0), u, atol=1e-12)
    assert np.linalg.norm(e1 - e0) == pytest.approx(m.parameters["link_tube_length_m"], rel=1e-12)
    # the guideway bar ends at the seat bottom, below B along the rail
    top = m.regions["lg_slider"]
    z = m.points[top.nodes] @ legs.e
    R, t = case.spherical_joint.ball_radius_m, case.solid.spherical_joint.seat_thickness_m
    assert np.allclose(z, B @ legs.e - R - t, atol=1e-12)
    for i, b in enumerate(m.bodies):
        assert is_watertight(m.tets[m.body_of_tet == i]), b.name
    assert (m.tet_volumes() > 0).all()  # proper rotations keep the orientation


def test_beam_sections_match_closed_forms(case):
    a = 0.01
    s = rectangle_section(a, a)
    # Roark: square torsion constant 0.1406 a^4; the CONVENTIONS formula is an approximation within 0.2 %
    assert s.Jt_m4 == pytest.approx(0.1406 * a**4, rel=2e-3)
    assert s.Ix_m4 == pytest.approx(a**4 / 12, rel=1e-15)
    t = tube_section(0.006, 0.005)
    assert t.Jt_m4 == pytest.approx(2 * t.Ix_m4, rel=1e-15)  # polar = 2 I for a round section
    assert t.A_m2 == pytest.approx(math.pi * (0.006**2 - 0.005**2) / 4, rel=1e-15)
    b = guideway_beam(case, 0.2, 10, A=case.base_points[1])
    assert b.length_m == pytest.approx(0.2, rel=1e-12)
    assert np.allclose(b.R.T @ b.R, np.eye(3), atol=1e-12)
    # local x of the guideway is radial (docs/conventions.md §2)
    radial = case.base_points[1] / np.linalg.norm(case.base_points[1])
    assert np.allclose(b.R[:, 0], radial, atol=1e-12)
    lb = link_beam(case, [0, 0, 0], [0.1, 0.05, 0.15], 8)
    assert len(lb.elements) == 8 and np.allclose(lb.R[:, 2] * np.linalg.norm([0.1, 0.05, 0.15]), [0.1, 0.05, 0.15])


def test_quality_measures_of_a_regular_tetrahedron():
    p = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float)
    t = np.array([[0, 1, 2, 3]])
    if np.linalg.det(p[1:] - p[0]) < 0:
        t = t[:, [0, 2, 1, 3]]
    # closed forms: dihedral angle arccos(1/3) = 70.53 deg, radius ratio 1 (round-off only)
    assert np.allclose(dihedral_angles_deg(p, t), math.degrees(math.acos(1 / 3)), atol=1e-9)
    assert radius_ratio(p, t)[0] == pytest.approx(1.0, abs=1e-12)
    assert is_watertight(t)
    assert not is_watertight(np.array([[0, 1, 2, 3], [0, 1, 2, 3]]))  # doubled tet: faces used twice
