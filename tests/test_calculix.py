"""CalculiX as an independent cross-check: C3D10 decks from femcheck meshes, results read back.

CalculiX is optional: the tests that run ``ccx`` are skipped with the module's reason where it is absent
(Debian/Ubuntu: ``apt-get install calculix-ccx``). The mesh conversion and the parsers are tested without it.
"""
from __future__ import annotations

import numpy as np
import pytest
import skfem

from femcheck.fe import calculix as cx

needs_ccx = pytest.mark.skipif(cx.ccx_executable() is None, reason=cx.SKIP_REASON)


def _box(n=3):
    x = np.linspace(0.0, 1.0, n + 1)
    return skfem.MeshTet.init_tensor(x, 0.5 * x, 2.0 * x)


def test_tet10_numbering_positive_corners_and_midpoints():
    mesh = _box()
    m10 = cx.tet10(mesh)
    X, el = m10.nodes, m10.elements
    a, b, c, d = (X[el[:, i]] for i in range(4))
    assert np.all(np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) > 0)
    for k, (i, j) in enumerate(cx.C3D10_EDGES):  # nodes 5..10 are the midpoints of edges 1-2, 2-3, 1-3, 1-4, 2-4, 3-4
        np.testing.assert_allclose(X[el[:, 4 + k]], 0.5 * (X[el[:, i]] + X[el[:, j]]), atol=1e-15)
    # every C3D10 node maps onto femcheck's P2 vector DOFs at the same location
    from femcheck.fe.elasticity import vector_basis
    basis = vector_basis(mesh, 2)
    nd = cx.node_dofs(basis, m10)
    for k in range(3):
        np.testing.assert_allclose(basis.doflocs[:, nd[:, k]].T, X, atol=1e-15)


def test_boundary_facets_map_to_their_element_face():
    mesh = _box()
    m10 = cx.tet10(mesh)
    bf = mesh.boundary_facets()
    el, face = cx.facet_faces(mesh, m10, bf)
    for e, f, fac in zip(el, face, bf):
        corners = m10.elements[e, list(cx.C3D10_FACES[f - 1])]
        assert set(corners) == set(mesh.facets[:, fac])


def test_dat_and_frd_parsers_read_ccx_layout(tmp_path):
    dat = """
 displacements (vx,vy,vz) for set NREF and time  0.1000000E+01

      6783  0.000000E+00  0.000000E+00 -1.235832E-06

 contact stress (slave element+face,press,tang1,tang2) for all contact elements and time 0.1000000E+01

       633          1  1.092490E+09  0.000000E+00  0.000000E+00
"""
    tb = cx.parse_dat(dat)
    assert [(t["title"], t["set"], t["time"]) for t in tb] == [("displacements (vx,vy,vz)", "NREF", 1.0),
                                                              ("contact stress (slave element+face,press,tang1,tang2)", "", 1.0)]
    assert tb[0]["rows"][0, 3] == pytest.approx(-1.235832e-06)
    frd = tmp_path / "x.frd"
    frd.write_text("  100CL  101 1.000000000        2                     0    1           1\n"
                   " -4  DISP        4    1\n"
                   " -5  D1          1    2    1    0\n"
                   " -1         1 1.00000E-06-2.00000E-06 3.00000E-06\n"
                   " -1         2-4.00000E-06 5.00000E-06-6.00000E-06\n"
                   " -3\n")
    ((t, vals),) = cx.parse_frd(frd, "DISP")
    assert t == 1.0 and sorted(vals) == [1, 2]
    np.testing.assert_allclose(vals[2], [-4e-6, 5e-6, -6e-6])


def test_missing_ccx_is_reported_not_raised(monkeypatch):
    monkeypatch.setenv("FEMCHECK_CCX", "/nonexistent/ccx-not-here")
    assert cx.ccx_executable() is None
    with pytest.raises(cx.CcxError, match="ccx not found"):
        cx.run("*HEADING\n", exe=None)


def test_bench_writes_a_skip_entry_without_ccx(monkeypatch):
    from femcheck.bench import calculix as bench
    fake = {"wall_s": 1.0, "dofs": 10, "factorizations": 1, "solver": "x",
            "loads": [{"force_N": F, "delta_error": 0.0, "a_error": 0.0, "a_fit_error": 0.0, "a_force_error": 0.0,
                       "force_ratio": 1.0, "iterations": 1} for F in (15.0, 50.0)]}
    monkeypatch.setattr(bench, "run_femcheck", lambda geometry, level=bench.LEVEL: fake)
    monkeypatch.setattr(cx, "ccx_executable", lambda: None)
    figs = bench.run()
    assert figs["ccx_status"] == cx.SKIP_REASON and "ccx_wall_s" not in figs
    assert "skipped: ccx not found" in bench.table(figs)


@needs_ccx
def test_cantilever_round_trip_matches_femcheck():
    """Independent check of femcheck's elasticity: the same P2 mesh, support and nodal loads in CalculiX (C3D10).

    Tolerance 1e-6 of max |u|: both codes discretize the same body with the same quadratic field, and C3D10's
    4-point rule integrates the straight-sided P2 stiffness exactly, as femcheck's degree-2 rule does, so the
    fields agree up to solver round-off and ccx's .dat print (7 significant digits: ≤ 5e-7 of a value).
    Measured: 5.2e-8. A wrong modulus, Poisson's ratio, DOF ordering or element orientation gives percent-level
    differences."""
    r = cx.cantilever_cross_check(10, 2)
    assert r["max_rel_diff"] < 1e-6, r
    assert r["tip_ccx_m"] == pytest.approx(r["tip_femcheck_m"], rel=1e-6)


@needs_ccx
def test_hertz_deck_round_trip_on_a_tiny_level(monkeypatch):
    """The Hertz side-by-side machinery on a 6.6k-DOF level (k = 2): CalculiX runs, its contact forces carry the
    whole load (the shared extraction K u on the block), and its approach is within 1 % of Hertz."""
    from femcheck.bench import calculix as bench
    from femcheck.fe.checks import hertz_sphere as hs
    monkeypatch.setitem(hs.LEVELS, "tiny", 2)
    r = bench.solve_ccx("tiny")
    for e in r["loads"]:
        assert e["force_ratio"] == pytest.approx(1.0, abs=1e-4)
        assert abs(e["delta_error"]) < 1e-2
        assert abs(e["a_force_error"]) < 5e-2
    assert r["iterations"] > 0 and r["wall_s"] > 0


@needs_ccx
def test_pin_in_bore_agrees_between_the_codes_on_a_small_mesh(monkeypatch):
    """Pin in a bore with clearance (conformal contact), 9.4k DOF: femcheck and CalculiX on one mesh.

    Code against code, no closed form. Measured on this mesh: pin displacement 0.6 % / 0.3 % apart and contact
    half-angle 1.7 % / 0.7 % apart at 100 / 400 N (at the bench's 52k DOF: 0.3 % / 0.15 % and 0.7 % / 0.3 %), so
    2 % and 4 % flag a real disagreement (a wrong load path, constraint or contact side), not mesh noise."""
    from femcheck.bench import _pin_bore as pb
    monkeypatch.setattr(pb, "CELLS", (3, 4, 32))
    f, c = pb.run_femcheck(), pb.run_ccx()
    for ef, ec in zip(f["loads"], c["loads"]):
        assert ef["force_ratio"] == pytest.approx(1.0, abs=1e-4) and ec["force_ratio"] == pytest.approx(1.0, abs=1e-4)
        assert ef["delta_m"] == pytest.approx(ec["delta_m"], rel=0.02)
        assert ef["theta_c_deg"] == pytest.approx(ec["theta_c_deg"], rel=0.04)
