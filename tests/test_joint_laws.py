"""FE-measured joint laws in the device FE.

Fast tests use laws sampled from known functions (their interpolation must be exact) and the coarse device FE
at P0; the slow test measures the real laws with the joints' contact FE."""
from __future__ import annotations

import numpy as np
import pytest

import femcheck
from femcheck.fe_device.joint_laws import JointLaws, MeasuredJointLaw, force_ladder

CASE = "cases/haptic_6psu.toml"


def sampled_law(joint: str, loads, approach, diag) -> MeasuredJointLaw:
    """A law through given ladder samples: approach (n,) m, diag (n, 6) stiffness diagonal."""
    K = np.zeros((len(loads), 6, 6))
    K[:, np.arange(6), np.arange(6)] = diag
    return MeasuredJointLaw(joint, "test", np.asarray(loads, float), np.asarray(approach, float), K, 0, 0, 0.0)


def closed_form_laws(case, compliance_scale: float = 1.0) -> JointLaws:
    """The closed-form joint laws of the device FE sampled on the force ladder, every compliance times
    ``compliance_scale`` (1: the same springs as the closed-form FE, so the device FE must not move)."""
    from femcheck.chain import device_parameters
    from femcheck.fe_device.joint_friction import joint_friction
    from femcheck.fe_device.loads import hertz_approach

    p, fr = device_parameters(case), joint_friction(case)
    F = force_ladder(case)
    c_uc, c_ub = float(np.squeeze(p.c_uc)), float(np.squeeze(p.c_ub))
    kt, ks, kp = fr.stick_stiffness(F)
    s = compliance_scale
    sp_diag = np.stack([np.ones_like(F), np.ones_like(F), np.ones_like(F), kt / s, kt / s, ks / s], axis=1)
    uj_diag = np.stack([np.full_like(F, 1 / (s * c_uc)), np.full_like(F, 1 / (s * c_uc)),
                        np.full_like(F, 1 / (s * (c_uc + c_ub))), kp / s, kp / s, np.ones_like(F)], axis=1)
    approach_sp = s * hertz_approach(F, float(np.squeeze(p.E_star_sp)), float(np.squeeze(p.R_star_sp)))
    return JointLaws(spherical=sampled_law("spherical", F, approach_sp, sp_diag),
                     universal=sampled_law("universal", F, s * (c_uc + c_ub) * F, uj_diag))


@pytest.mark.parametrize("seed", range(4))
def test_power_law_interpolation_is_exact_for_hertz_and_linear_springs(seed):
    """δ = c F^p (Hertz p = 2/3, a linear spring p = 1) is reproduced exactly between, below and above the
    ladder (piecewise power law), and K ∝ F^(1/3) (Mindlin stick ∝ a) too inside it; rtol 1e-12: round-off."""
    rng = np.random.default_rng(seed)
    F = np.sort(rng.uniform(0.2, 40.0, 6))
    p, c = rng.choice([2 / 3, 1.0]), rng.uniform(1e-7, 1e-5)
    diag = np.tile(rng.uniform(1e3, 1e6, 6), (F.size, 1)) * (F[:, None] / F[0]) ** (1 / 3)
    law = sampled_law("spherical", F, c * F**p, diag)
    Fq = np.concatenate([rng.uniform(F[0], F[-1], 20), [0.5 * F[0], 2 * F[-1]]])
    np.testing.assert_allclose(law.approach(Fq), c * Fq**p, rtol=1e-12)
    np.testing.assert_allclose(law.secant(Fq), Fq / (c * Fq**p), rtol=1e-12)
    inside = Fq[:20]
    np.testing.assert_allclose(law.component_stiffness(inside),
                               diag[0] * (inside[:, None] / F[0]) ** (1 / 3), rtol=1e-12)


def test_a_law_whose_approach_does_not_grow_is_refused():
    """A contact FE that lost the joint (approach not increasing with load) is an error, never a law."""
    with pytest.raises(ValueError, match="approach must grow"):
        sampled_law("universal", [1.0, 2.0, 4.0], [3e-6, 2e-6, 5e-6], np.ones((3, 6)))
    with pytest.raises(ValueError, match="increasing positive"):
        sampled_law("universal", [2.0, 1.0], [1e-6, 2e-6], np.ones((2, 6)))


def test_cache_round_trip(tmp_path, monkeypatch):
    """A stored law reads back identically (and says it came from the cache)."""
    from femcheck.fe_device import joint_laws as jl
    monkeypatch.setenv("FEMCHECK_CACHE", str(tmp_path))
    law = closed_form_laws(femcheck.load_case(CASE)).spherical
    path = jl._cache_path("abc")
    jl._store(path, law)
    back = jl._load(path, "spherical", "test")
    assert back.cached and np.array_equal(back.stiffness, law.stiffness) and np.array_equal(back.approach_m, law.approach_m)


def test_cache_key_follows_the_universal_mesh_levels(monkeypatch):
    """A change of the universal joint's mesh levels (here its axial element length) changes the law's
    cache key, so no stale law is reused; the other joint and level keep theirs."""
    from femcheck.fe_device import joint_laws as jl
    from femcheck.fe_device import mesh_levels
    case = femcheck.load_case(CASE)
    ladder = np.geomspace(0.5, 25.0, 7)
    before = {(j, m): jl._cache_key(case, j, m, ladder) for j in ("universal", "spherical") for m in ("coarse", "fine")}
    monkeypatch.setitem(mesh_levels.UNIVERSAL_AXIAL_FACTOR, "coarse", 1.7)
    after = {k: jl._cache_key(case, *k, ladder) for k in before}
    assert after[("universal", "coarse")] != before[("universal", "coarse")]
    assert all(after[k] == before[k] for k in before if k != ("universal", "coarse"))


@pytest.fixture(scope="module")
def p0_model(coarse_p0_fe_models):
    return coarse_p0_fe_models["P0"]


def _deflections(case, model, laws):
    from femcheck.fe_device.device_model import solve_point
    r = solve_point(case, model, ("detailed",), joint_laws=laws)
    return {k: c.deflection_m for k, c in r.cases.items()}


def test_device_fe_with_closed_form_sampled_laws_reproduces_the_closed_form_fe(p0_model):
    """Wiring check (agreement by construction): laws sampled from the closed forms give the closed-form device FE
    for rigid, released and contact joints; rtol 1e-7: the two secant fixed points stop at 1e-10 relative
    change from different starts."""
    case = femcheck.load_case(CASE)
    ref = _deflections(case, p0_model, None)
    got = _deflections(case, p0_model, closed_form_laws(case))
    for k in ref:
        assert got[k] == pytest.approx(ref[k], rel=1e-7), k


def test_device_fe_moves_with_the_measured_law_not_with_the_closed_form(p0_model):
    """With a joint law 30 % more compliant the released deflection grows by about the joints' share x 30 %
    (8.5 % + 8 % shares, docs/conventions.md §7: expect 3-8 %); and a mutation of the closed form
    ([model.law_scale]) no longer moves the FE at all (rtol 1e-12)."""
    case = femcheck.load_case(CASE)
    laws = closed_form_laws(case)
    base = _deflections(case, p0_model, laws)
    soft = _deflections(case, p0_model, closed_form_laws(case, 1.3))
    for d in case.loads.directions:
        k = ("detailed", "released", d)
        assert 1.02 < soft[k] / base[k] < 1.10, (k, soft[k] / base[k])
    mutated = case.with_params(**{"model.law_scale.sp": 2.0, "model.law_scale.uj": 2.0})
    again = _deflections(mutated, p0_model, laws)
    for k in base:
        assert again[k] == pytest.approx(base[k], rel=1e-12), k


def test_coverage_names_contact_fe_joints_and_covers_them(p0_model):
    """Issue 22: with the joints' FE laws and the actuation as elements (the reference case), no element of the
    detailed chain is a shared closed form: the joints are 'contact_fe' (from behaviour: the FE does not move
    with the mutated law), the independent share is 100 %; without the joint laws they are shared again."""
    from femcheck.coverage import element_coverage
    case = femcheck.load_case(CASE)
    laws = closed_form_laws(case, 0.9)
    res = element_coverage(case, ("P0",), 50.0, "coarse", fe_models={"P0": p0_model}, joint_laws=laws)
    by = {e.element: e for e in res.elements}
    assert by["spherical_joint"].fe_source == "contact_fe" and by["universal_joint"].fe_source == "contact_fe"
    assert by["spherical_joint"].fe_response_ratio < 1e-6 and by["actuation"].fe_source == "meshed"
    assert res.independent_share_pct == pytest.approx(100.0) and res.joint_laws == {"spherical": "contact_fe", "universal": "contact_fe"}
    # covered: only what +50 % makes the check fail on (the 1.4 % proximal link is not caught at +50 %)
    assert res.covered_share_pct == pytest.approx(sum(e.share_pct for e in res.elements if e.detected))
    shared = element_coverage(case, ("P0",), 50.0, "coarse", fe_models={"P0": p0_model})
    by = {e.element: e for e in shared.elements}
    assert by["spherical_joint"].fe_source == "shared_closed_form" and by["universal_joint"].fe_source == "shared_closed_form"
    assert shared.covered_share_pct < 90.0 and shared.independent_share_pct < 90.0


@pytest.mark.slow
def test_measured_laws_against_hertz_and_the_clearance(tmp_path, monkeypatch):
    """The real contact FE (coarse): the ball's eq. 1 secant over the ladder lies within 15 % of Hertz's
    (measured −4 to −10 % over the mesh levels, docs/verify.md), and the U joint's approach at the smallest
    force has taken up most of the 2c radial clearance (the cross floats across it before any stiffness)."""
    from femcheck.fe_device.joint_laws import measure_joint_laws
    from femcheck.fe_device.loads import hertz_approach
    from femcheck.chain import device_parameters
    monkeypatch.setenv("FEMCHECK_CACHE", str(tmp_path))
    case = femcheck.load_case(CASE)
    laws = measure_joint_laws(case, "coarse")
    p = device_parameters(case)
    F5, F20 = 4.0, 16.0
    hz = hertz_approach(np.array([F5, F20]), float(np.squeeze(p.E_star_sp)), float(np.squeeze(p.R_star_sp)))
    fe = laws.spherical.approach(np.array([F5, F20]))
    assert abs((fe[1] - fe[0]) / (hz[1] - hz[0]) - 1) < 0.15
    c = float(case.solid.universal_joint.pin_clearance_m)
    assert 1.0 * c < laws.universal.approach_m[0] < 2.0 * c + 5e-6
    assert laws.sources() == {"spherical": "contact_fe", "universal": "contact_fe"}


def test_extended_case_puts_the_measured_ratio_into_the_analytical_joint_laws(tmp_path):
    """check-joints --extended-case: the written case loads, its analytical joint compliances are the closed forms
    times the FE / closed-form ratio (rtol 1e-5: the ratio is written with 6 significant digits), and a case
    that already sets [model.law_scale] is refused."""
    from pathlib import Path
    from femcheck.chain import device_parameters
    from femcheck.errors import FemcheckError
    from femcheck.fe_device.joint_check import extended_case_text
    results = [{"joint": "spherical", "mesh": "coarse", "point": "P0", "fe_component_compliance": [0, 0, 1.4e-6],
                "analytical_compliance": [[0] * 3, [0] * 3, [0, 0, 1.6e-6]]},
               {"joint": "universal", "mesh": "coarse", "point": "P0", "fe_component_compliance": [0, 0, 8.0e-7],
                "analytical_compliance": [[0] * 3, [0] * 3, [0, 0, 1.6e-6]]}]
    text = Path(CASE).read_text()
    out = tmp_path / "extended.toml"
    out.write_text(extended_case_text(text, CASE, results))
    base, ext = device_parameters(femcheck.load_case(CASE)), device_parameters(femcheck.load_case(out))
    c = lambda p: float(np.squeeze(p.c_uc)) + float(np.squeeze(p.c_ub))
    assert c(ext) / c(base) == pytest.approx(0.5, rel=1e-5)
    # Hertz compliance ~ E*^(-2/3): a compliance factor s scales E* by s^(-3/2)
    assert float(np.squeeze(ext.E_star_sp)) / float(np.squeeze(base.E_star_sp)) == pytest.approx(0.875 ** -1.5, rel=1e-5)
    with pytest.raises(FemcheckError, match="already set"):
        extended_case_text(out.read_text(), str(out), results)


def test_extended_case_cli_refuses_a_case_with_law_scale_before_any_fe(tmp_path, capsys):
    """Bad input: --extended-case on a case that already sets [model.law_scale] exits 2 with one line naming the
    file, before any joint FE runs, and writes nothing."""
    from pathlib import Path
    from femcheck.cli import main
    case = tmp_path / "scaled.toml"
    case.write_text(Path(CASE).read_text() + "\n[model.law_scale]\nsp = 1.1\n")
    out = tmp_path / "ext.toml"
    assert main(["check-joints", str(case), "--extended-case", str(out)]) == 2
    err = capsys.readouterr().err
    assert "already set" in err and str(case) in err and "Traceback" not in err
    assert not out.exists()
