"""Contact verification problems against closed forms (issue 5 acceptance): patch test, friction block,
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
    # Coulomb limit Σ w‖t‖ = μ Σ w p = μN, to the residual tolerance (1e-8 relative -> 1e-5 margin)
    assert r.rel_error < 1e-5
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


def test_hertz_sphere_coarse_approach_and_depth_independence():
    from femcheck.fe.checks import hertz_sphere as hs

    model = hs.build("coarse")
    res = hs.solve(model)
    for e in hs.evaluate(model, res):
        # coarse mesh (30 µm elements, 2.5–4 per contact radius): approach within 2 %, radius within 8 %
        assert e["delta_rel_error"] < 0.02
        assert e["a_rel_error"] < 0.08
        assert e["contact_force_N"] == pytest.approx(e["force_N"], rel=1e-6)  # equilibrium
        # depth extraction: approach of axis points + 2 v(d) agrees with δ = −Δ within 1.5 % at every depth
        assert e["depth_extraction"]
        for d in e["depth_extraction"]:
            assert d["delta_m"] == pytest.approx(e["delta_m"], rel=0.015)


def test_check_solver_cli_json_contact_patch():
    from typer.testing import CliRunner

    from femcheck.cli import get_app

    out = CliRunner().invoke(get_app(), ["check-solver", "contact-patch", "--mesh", "coarse", "--json"])
    assert out.exit_code == 0, out.output
    rows = json.loads(out.output)
    assert rows[0]["name"] == "contact-patch"
    assert set(rows[0]) >= {"name", "computed", "reference", "rel_error", "dofs", "iterations", "seconds"}
    assert rows[0]["rel_error"] < 1e-6  # the patch test is exact to round-off


@pytest.mark.slow
def test_hertz_sphere_default_acceptance_and_penalty_independence():
    from femcheck.fe.checks import hertz_sphere as hs

    model = hs.build("default")
    res = hs.solve(model)
    ev = hs.evaluate(model, res)
    for e in ev:
        assert e["delta_rel_error"] < 0.02  # acceptance: approach within 2 % at the default refinement
        assert e["a_rel_error"] < 0.05      # acceptance: contact radius within 5 %
    stiff = hs.build("default", penalty_factor=10 * 100.0)
    ev10 = hs.evaluate(stiff, hs.solve(stiff))
    for e, e10 in zip(ev, ev10):
        # acceptance: ×10 penalty changes the approach by < 1 % with the augmented-Lagrangian update
        assert abs(e10["delta_m"] - e["delta_m"]) / e["delta_m"] < 0.01


@pytest.mark.slow
def test_hertz_sphere_refinement_study():
    from femcheck.fe.checks import hertz_sphere as hs

    errs = {}
    for level in ("coarse", "default"):
        m = hs.build(level)
        errs[level] = [e["delta_rel_error"] for e in hs.evaluate(m, hs.solve(m))]
    # refinement reduces the worse approach error of the two loads
    assert max(errs["default"]) < max(errs["coarse"])


@pytest.mark.slow
def test_hertz_cylinder_default():
    from femcheck.fe.checks import hertz_cylinder as hc

    r = hc.run("default")
    assert r.rel_error < 0.01  # 10 µm elements at a ≈ 105 µm: half-width within 1 %
    lo, hi = r.detail["a_bracket_m"]
    assert lo <= r.reference <= hi
