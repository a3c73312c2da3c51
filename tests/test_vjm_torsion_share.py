"""Torsion share of the deflection (seed 002 §V): exact superposition, its limits, and the figures the docs
quote, computed here."""
from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

import femcheck
from femcheck.vjm.serial_vjm import deflect
from femcheck.vjm.torsion_share import spring_deflections, torsion_share

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def cobot():
    case = femcheck.load_case(ROOT / "cases" / "cobot7.toml")
    ident = case.identification
    q = np.radians(np.array(ident.configurations_deg + ident.verification_configurations_deg))
    return case, case.vjm(extended=True), q, ident.wrenches


def test_table_i_has_the_papers_13_configurations(cobot):
    _, _, q, _ = cobot
    assert q.shape == (13, 7)                     # seed 002 Table I: 8 identification + 5 verification
    assert np.all(q[10] == 0)                     # configuration 11 is the singular zero pose


def test_share_is_the_torsion_part_of_the_vjm_deflection(cobot):
    """dX = sum of the springs' parts (no K_C): total of the split equals femcheck's deflection to round-off,
    and stiffening the tilt springs 1e6x drives the share to 1 (torsion alone), the torsion springs to 0."""
    _, model, q, wrenches = cobot
    W = np.asarray(wrenches[0])
    d = deflect(model, q, W, complementary=False, stiffness=False).twist[:, :3]
    k = np.asarray(model.k_theta)
    tilt_stiff = dataclasses.replace(model, k_theta=tuple(np.where(np.arange(k.size) % 3 == 0, k, 1e6 * k)))
    torsion_stiff = dataclasses.replace(model, k_theta=tuple(np.where(np.arange(k.size) % 3 == 0, 1e6 * k, k)))
    assert np.all(torsion_share(tilt_stiff, q, W) > 1 - 1e-4)      # 1e6 stiffer tilt: share 1 - O(1e-6) (12 is singular-ish)
    assert np.all(torsion_share(torsion_stiff, q, W) < 1e-4)
    s = torsion_share(model, q, W)
    assert np.all((s > 0) & (s < 1))
    # the springs' parts add up to femcheck's VJM deflection (seed 003 eq. 15 without K_C): round-off only
    parts = spring_deflections(model, q, W)
    np.testing.assert_allclose(parts.sum(axis=2), d, rtol=1e-10, atol=1e-12 * np.abs(d).max())


def test_docs_quote_the_computed_shares(cobot):
    _, model, q, wrenches = cobot
    S = np.array([torsion_share(model, q, W) for W in wrenches])     # (2 wrenches, 13 configurations)
    per_config = S.mean(axis=0)
    mean, hi, lo = 100 * S.mean(), 100 * per_config.max(), 100 * per_config.min()
    text = " ".join((ROOT / "docs" / "vjm.md").read_text().split())
    m = re.search(r"torsion springs give ([\d.]+) % of the deflection on average .*?at most ([\d.]+) %, "
                  r"configuration (\d+); at least ([\d.]+) %, configuration (\d+)\)", text)
    assert m, "docs/vjm.md must quote the torsion share"
    # the docs print one decimal: agree to rounding
    assert float(m.group(1)) == pytest.approx(mean, abs=0.05)
    assert float(m.group(2)) == pytest.approx(hi, abs=0.05) and int(m.group(3)) == int(np.argmax(per_config)) + 1
    assert float(m.group(4)) == pytest.approx(lo, abs=0.05) and int(m.group(5)) == int(np.argmin(per_config)) + 1
