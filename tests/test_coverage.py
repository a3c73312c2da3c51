"""Verification coverage by mutation: a meshed element's wrong law is caught, a law the
FE reuses is not, and fe_source comes from behaviour."""
from __future__ import annotations

import pytest

import femcheck
from femcheck.coverage import element_coverage


@pytest.fixture(scope="module")
def fe_models(coarse_p0_fe_models):
    """The coarse FE super-elements at P0, built once per session (no law mutation or actuation option changes them)."""
    return coarse_p0_fe_models


def _law_actuation():
    """The reference case with the device FE taking eq. 44's spring itself (``[actuation.fe] model = "law"``)."""
    return femcheck.load_case("cases/haptic_6psu.toml").with_params(**{"actuation.fe.model": "law"})


@pytest.fixture(scope="module")
def coverage(fe_models):
    """Closed-form joint laws and the eq. 44 actuation spring on the FE side: three shared laws."""
    return element_coverage(_law_actuation(), points=("P0",), mutation_pct=50.0, mesh="coarse", fe_models=fe_models)


def test_law_scale_multiplies_the_element_compliance_exactly():
    """[model.law_scale] acts on the law: the guideway element compliance doubles with scale 2 (beam terms are
    1/E or 1/G), the actuation spring too, and the Hertz compliance through E*^(-3/2) (k ~ E*^(2/3))."""
    import numpy as np
    from femcheck.chain import device_parameters
    case = femcheck.load_case("cases/haptic_6psu.toml")
    p0 = device_parameters(case)
    p2 = device_parameters(case.with_params(**{"model.law_scale.act": 2.0, "model.law_scale.sp": 2.0,
                                               "model.law_scale.lg": 2.0}))
    assert p2.c_act == pytest.approx(2 * p0.c_act, rel=1e-12)
    assert p2.E_lg == pytest.approx(p0.E_lg / 2, rel=1e-12) and p2.G_lg == pytest.approx(p0.G_lg / 2, rel=1e-12)
    k = lambda E: (6 * E**2 * float(np.squeeze(p0.R_star_sp)) * 10.0) ** (1 / 3)   # Hertz tangent at 10 N
    assert k(p0.E_star_sp) / k(p2.E_star_sp) == pytest.approx(2.0, rel=1e-12)


def test_meshed_element_is_detected_and_shared_law_is_not(coverage):
    by = {e.element: e for e in coverage.elements}
    # the guideways are meshed solids: the FE does not move with the law (ratio 0 to round-off)
    assert by["guideway"].fe_source == "meshed" and by["guideway"].fe_response_ratio < 1e-6
    assert by["guideway"].detected
    # with model = "law" the actuation spring is the analytical law itself in the device FE: it moves alike, unseen
    assert by["actuation"].fe_source == "shared_closed_form"
    assert not by["actuation"].detected and by["actuation"].min_detectable_pct is None
    # min detectable mutation by linearization: between 0 and the applied 50 % for a detected element
    assert 0 < by["guideway"].min_detectable_pct < 50


def test_shares_sum_to_100_and_covered_share_is_the_detected_share(coverage):
    """covered_share_pct counts only what the check catches at the stated mutation; independent_share_pct what
    the FE models on its own, caught or not. The proximal link is meshed but too small a share to move the mean
    error past 10 % at +50 %: independent, not covered."""
    assert sum(e.share_pct for e in coverage.elements) == pytest.approx(100.0, abs=1e-6)  # energy shares sum to 1
    independent = [e for e in coverage.elements if e.fe_source != "shared_closed_form"]
    assert coverage.covered_share_pct == pytest.approx(sum(e.share_pct for e in independent if e.detected))
    assert coverage.independent_share_pct == pytest.approx(sum(e.share_pct for e in independent))
    prox = next(e for e in coverage.elements if e.element == "proximal_link")
    assert prox.fe_source == "meshed" and not prox.detected
    assert coverage.covered_share_pct <= coverage.independent_share_pct - prox.share_pct + 1e-9
    assert coverage.base_error_pct < 10.0  # the unmutated model passes the check


def test_coverage_cli_json_keys(tmp_path):
    import json
    from femcheck.cli import main
    out = tmp_path / "cov.json"
    assert main(["coverage", "cases/haptic_6psu.toml", "--points", "P0", "--mutation", "50", "--no-joint-fe",
                 "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert {"mutation_pct", "covered_share_pct", "independent_share_pct", "elements"} <= set(doc)
    assert {"element", "share_pct", "fe_source", "error_change_pct", "detected", "min_detectable_pct"} <= set(doc["elements"][0])


def _actuation_fe(**opts):
    return femcheck.load_case("cases/haptic_6psu.toml").with_params(
        **{"actuation.fe.model": "elements", **{f"actuation.fe.{k}": v for k, v in opts.items()}})


def test_actuation_fe_makes_the_actuation_meshed_and_detected(fe_models, coverage):
    """Issue 22 item 2: with the actuation as elements (eq. 44's single-strand layout, which the elements reproduce
    exactly, so the unmutated pair still passes) a wrong actuation law is caught and counts as covered."""
    res = element_coverage(femcheck.load_case("cases/haptic_6psu.toml"), points=("P0",), mutation_pct=50.0,
                           mesh="coarse", fe_models=fe_models)   # the reference case: elements, single strand
    by = {e.element: e for e in res.elements}
    assert by["actuation"].fe_source == "meshed" and by["actuation"].fe_response_ratio < 1e-6
    assert by["actuation"].detected and 0 < by["actuation"].min_detectable_pct < 50
    # the base moves only by the pretension's transverse geometric stiffness on the guideways (P0, P5: 0.83 -> 0.91 %)
    assert res.base_passes and res.base_error_pct == pytest.approx(coverage.base_error_pct, abs=0.3)
    assert res.covered_share_pct == pytest.approx(coverage.covered_share_pct + by["actuation"].share_pct)
    assert res.independent_share_pct == pytest.approx(coverage.independent_share_pct + by["actuation"].share_pct)


def test_closed_loop_actuation_fe_fails_eq44_and_coverage_says_so(fe_models):
    """The case's closed cable loop puts two strands in parallel: the FE is much stiffer than eq. 44's single
    strand, the unmutated check fails (a finding, docs/verify.md), and coverage flags its base as failing."""
    res = element_coverage(_actuation_fe(layout="closed_loop"), points=("P0",), mutation_pct=50.0, mesh="coarse",
                           fe_models=fe_models)
    assert not res.base_passes and res.base_error_pct > 30.0          # measured 55 % (P0, coarse, +x)
    by = {e.element: e for e in res.elements}
    assert by["actuation"].fe_source == "meshed" and by["actuation"].min_detectable_pct == 0.0
    # a base that already fails cannot tell a mutation from its own disagreement: nothing counts as caught
    assert res.covered_share_pct == 0.0 and not any(e.detected for e in res.elements)
    assert res.independent_share_pct > 50.0


def test_coverage_cli_set_override():
    from femcheck.cli.coverage import parse_overrides
    assert parse_overrides(["actuation.fe.model=elements", "actuation.fe.cable_pretension_N=80",
                            'actuation.fe.layout="single_strand"']) == {
        "actuation.fe.model": "elements", "actuation.fe.cable_pretension_N": 80, "actuation.fe.layout": "single_strand"}
