"""Contact verification problems against closed forms: patch test, friction block,
Hertz line and point contact, penalty independence, refinement study, ``check-solver`` CLI."""
from __future__ import annotations

import json

import numpy as np
import pytest

from femcheck.fe.contact import status as st


def test_patch_test_transmits_uniform_pressure():
    from femcheck.fe.checks import contact_patch

    r = contact_patch.run("coarse")
    # acceptance: uniform pressure to 1e-6 relative (exact FE solution; only round-off remains)
    assert r.detail["max_rel_deviation"] < 1e-6
    assert r.rel_error < 1e-6


def test_friction_block_sticks_below_and_slides_at_mu_n():
    from femcheck.fe.checks import friction_block as fb

    r = fb.run("coarse")
    stick, slide = r.detail["stick"], r.detail["slide"]
    n_pts = sum(stick["status"].values())
    assert stick["status"]["stick"] == n_pts                      # every point sticks at T = 0.5 μN
    # x-equilibrium of the upper block: friction = applied T (solver tolerance 1e-8 on forces -> 1e-6)
    assert stick["friction_force_x_N"] == pytest.approx(stick["applied_T_N"], rel=1e-6)
    # AL update: no residual slip beyond the penetration tolerance (1e-4 of max|u| ≈ 1e-10 m here)
    assert stick["max_stick_slip_m"] < 1e-9
    assert slide["status"]["slide"] == sum(slide["status"].values())  # every point slides
    # the horizontal reaction at the displaced top face (global equilibrium, not the return mapping) is μN
    # up to the y share of friction from the Poisson mismatch (measured 9.4e-6 relative at coarse)
    assert r.rel_error < 1e-4
    assert r.computed < r.reference  # the y share can only lower the x resultant
    assert r.rel_error <= fb.TOLERANCE["coarse"]
    assert slide["normal_force_N"] == pytest.approx(fb.N_LOAD, rel=1e-6)


def test_hertz_cylinder_half_width_coarse():
    from femcheck.fe.checks import hertz_cylinder as hc

    r = hc.run("coarse")
    # coarse mesh (15 µm at a ≈ 105 µm): the closed area per thickness within 2 %
    assert r.rel_error < 0.02
    lo, hi = r.detail["a_bracket_m"]
    # the Hertz half-width lies between the outermost closed and innermost open Gauss point (≤ 1 spacing)
    assert lo <= r.reference <= hi
    # vertical equilibrium: the contact carries P' (solver tolerance)
    assert r.detail["force_per_length_N_m"] == pytest.approx(hc.P_LINE, rel=1e-6)


def test_hertz_sphere_mesh_is_a_conforming_o_grid():
    from femcheck.fe.checks import hertz_sphere as hs

    m = hs.level_mesh("coarse")
    p, t = m.p, m.t
    a, b, c, d = (p[:, t[i]] for i in range(4))
    vol = np.einsum("ij,ij->j", np.cross(b - a, c - a, axis=0), d - a) / 6.0
    assert vol.min() > 0.0                                           # positively oriented tets
    assert vol.sum() == pytest.approx(hs.L**3, rel=1e-12)            # the cube [0, L]³, no gaps or overlaps
    # conforming: every boundary facet lies on a face of the cube (an unmatched interior facet would not)
    fc = p[:, m.facets[:, m.boundary_facets()]].mean(axis=1)
    assert np.all(np.isclose(fc, 0.0, atol=1e-15).any(axis=0) | np.isclose(fc, hs.L, rtol=1e-12).any(axis=0))


def test_hertz_sphere_coarse_approach_and_depth_independence():
    from femcheck.fe.checks import hertz_sphere as hs

    model = hs.build("coarse")
    res = hs.solve(model)
    for e in hs.evaluate(model, res):
        # coarse (k = 3, cells ≈ a/3 at the contact edges): measured −0.56 / −0.63 %, FE stiffer than Hertz
        assert -0.01 < e["delta_error"] < 0.0
        assert e["a_rel_error"] < 0.08  # outermost closed Gauss point: measured −4.0 / −5.2 %
        assert e["contact_force_N"] == pytest.approx(e["force_N"], rel=1e-6)  # equilibrium
        # depth extraction: approach of axis points + 2 v(d) agrees with δ = −Δ at every depth
        # (measured ≤ 0.17 % at 0.35–0.9 mm; 0.5 % leaves room for the coarse growth layers)
        assert e["depth_extraction"]
        for d in e["depth_extraction"]:
            assert d["delta_m"] == pytest.approx(e["delta_m"], rel=0.005)


def test_check_solver_cli_json_contact_patch():
    from typer.testing import CliRunner

    from femcheck.cli import get_app

    out = CliRunner().invoke(get_app(), ["check-solver", "contact-patch", "--mesh", "coarse", "--json", "-"])
    assert out.exit_code == 0, out.output
    rows = json.loads(out.stdout)   # the progress lines go to standard error
    assert rows[0]["name"] == "contact-patch"
    assert set(rows[0]) >= {"name", "computed", "reference", "rel_error", "tolerance", "passed", "dofs", "iterations",
                            "seconds"}
    assert rows[0]["rel_error"] < 1e-6  # the patch test is exact to round-off
    assert rows[0]["passed"] is True


def test_check_solver_exits_1_when_a_problem_is_outside_its_tolerance(monkeypatch):
    """Mutation: tighten a tolerance below the attained error; the command must fail and say which."""
    from typer.testing import CliRunner

    from femcheck.cli import get_app
    from femcheck.fe.checks import bar_modal

    monkeypatch.setitem(bar_modal.TOLERANCE, "coarse", 1e-6)   # attained 3.2e-3 at coarse
    out = CliRunner().invoke(get_app(), ["check-solver", "bar-modal", "--mesh", "coarse", "--json", "-"])
    assert out.exit_code == 1
    assert "bar-modal" in out.output


@pytest.mark.slow
def test_hertz_sphere_default_acceptance_and_penalty_independence():
    from femcheck.fe.checks import hertz_sphere as hs

    model = hs.build("default")
    res = hs.solve(model)
    ev = hs.evaluate(model, res)
    for e in ev:
        assert e["delta_rel_error"] < 0.02  # acceptance: approach within 2 % at the default refinement
        assert e["delta_rel_error"] < 0.01  # bench target ≤ 1 % (measured −0.24 / −0.22 %)
        assert e["a_rel_error"] < 0.05      # acceptance: contact radius within 5 %
    stiff = hs.build("default", penalty_factor=10 * 100.0)
    ev10 = hs.evaluate(stiff, hs.solve(stiff))
    for e, e10 in zip(ev, ev10):
        # acceptance: ×10 penalty changes the approach by < 1 % with the augmented-Lagrangian update
        assert abs(e10["delta_m"] - e["delta_m"]) / e["delta_m"] < 0.01


@pytest.mark.slow
def test_hertz_sphere_refinement_study():
    from femcheck.fe.checks import hertz_sphere as hs

    levels = ("coarse", "default", "fine")
    errs = {}
    for level in levels:  # fine: 87k DOFs, 70–90 s on 2 shared cores
        m = hs.build(level)
        errs[level] = [e["delta_error"] for e in hs.evaluate(m, hs.solve(m))]
    for i, F in enumerate(hs.LOADS_N):
        e = [errs[level][i] for level in levels]
        # displacement FE of the exact Hertz problem (half-spaces + sphere gap; truncating at L moves δ by
        # ≤ 4e-5, measured): stiffer than Hertz at every level, and the error shrinks monotonically
        assert all(x < 0.0 for x in e), (F, e)
        assert abs(e[0]) > abs(e[1]) > abs(e[2]), (F, e)
        # at a consistent rate (cell sizes ∝ 1/k): measured orders 3.0–4.5; the contact-edge singularity
        # (u ~ ρ^1.5) allows ~3 for the energy-like approach error, > 2 leaves room for the coarse level
        for j in range(2):
            k0, k1 = hs.LEVELS[levels[j]], hs.LEVELS[levels[j + 1]]
            assert np.log(e[j] / e[j + 1]) / np.log(k1 / k0) > 2.0, (F, e)


@pytest.mark.slow
def test_hertz_sphere_curved_mesh_variant_coarse():
    from femcheck.fe.checks import hertz_sphere as hs

    r = hs.run("coarse", geometry="sphere")
    for e in r.detail["loads"]:
        # the sphere carried by the mesh (not the Hertz half-space idealization): measured +0.58 / +0.39 %
        assert e["delta_rel_error"] < 0.02
        assert e["contact_force_N"] == pytest.approx(e["force_N"], rel=1e-6)


@pytest.mark.slow
def test_hertz_cylinder_default():
    from femcheck.fe.checks import hertz_cylinder as hc

    r = hc.run("default")
    assert r.rel_error < 0.01  # 10 µm elements at a ≈ 105 µm: half-width within 1 %
    lo, hi = r.detail["a_bracket_m"]
    assert lo <= r.reference <= hi


def test_check_solver_help_lists_every_problem():
    """`check-solver --help` names every registered problem with what it checks."""
    from typer.testing import CliRunner

    from femcheck.cli import get_app
    from femcheck.fe.checks import registry, summaries

    out = CliRunner().invoke(get_app(), ["check-solver", "--help"], env={"COLUMNS": "200"})
    assert out.exit_code == 0, out.output
    for name, text in summaries().items():
        assert name in out.output and text.split()[0] in out.output, name
    assert set(summaries()) == set(registry()) and len(registry()) >= 7
