"""The ``measured_law`` joint element of parallel devices.

A joint's 6 x 6 compliance measured by the joint contact FE (``femcheck check-joints --json``) enters the leg at
the joint centre in the frame of the adjacent link. Checked against the closed-form elements it can stand for,
against springs in series, between the numpy and compiled paths and the beam FE, and for bad input.
"""
from __future__ import annotations

import copy
import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from femcheck.case import load_case
from femcheck.case.registry import build_case
from femcheck.errors import CaseError
from femcheck.parallel.beam_fe import device_fe_stiffness
from femcheck.parallel.chain_model import evaluate
from femcheck.parallel.device import test_points as cube_points

ROOT = Path(__file__).resolve().parents[1]
HEXAPOD = ROOT / "cases" / "hexapod_6ups.toml"
DELTA = ROOT / "cases" / "delta_3ruu.toml"
MEASURED = ROOT / "cases" / "haptic_6psu_legs_measured.toml"
LAW = ROOT / "cases" / "laws" / "haptic_6psu_spherical_coarse.json"
#: the rotation entries of a law standing in for a translational element: 1e-15 rad/(N m) is 1e-13 of the links'
#: rotational compliance (about 1e-2 rad/(N m)), so it moves K_T by about 1e-13 relative where it enters at all
EPS_ROT = 1e-15
#: same equations by two routes in double precision: only rounding separates them
RTOL = 1e-9
WRENCH = [3.0, -2.0, 10.0, 0.1, 0.0, 0.2]


def _raw(path):
    with open(path, "rb") as f:
        return tomllib.load(f)


def _random_poses(case, n, seed, dx=0.015, drot=0.05):
    rng = np.random.default_rng(seed)
    P = np.tile(cube_points(case)[0], (n, 1))
    P[:, :3] += rng.uniform(-dx, dx, (n, 3))
    if case.device.n_legs == 6:   # the Delta is translational
        P[:, 3:] = rng.uniform(-drot, drot, (n, 3))
    return np.vstack([cube_points(case), P])


def _rel(a, b):
    return float(np.abs(a - b).max() / np.abs(b).max())


def _line_as_law(path, tmp_path):
    """The case at ``path`` and its variant whose every hertz_line is a measured_law JSON file (check-joints format)
    with the same compliance: diag(c_uc, c_uc, c_uc + c_ub) on the translations, EPS_ROT on the rotations."""
    base = load_case(path)
    raw = _raw(path)
    for i, leg in enumerate(raw["legs"]):
        for k, j in enumerate(leg["joints"]):
            if "hertz_line" in j:
                c_uc, c_ub, _ = base.device.legs[i].hertz_line[k]
                S = np.diag([c_uc, c_uc, c_uc + c_ub, EPS_ROT, EPS_ROT, EPS_ROT])
                name = f"law_{i}_{k}.json"
                (tmp_path / name).write_text(json.dumps([{"joint": "universal", "fe_compliance": S.tolist()}]))
                del j["hertz_line"]
                j["measured_law"] = {"file": name}
    return base, build_case(raw, tmp_path / "variant.toml")


@pytest.mark.parametrize("path", [HEXAPOD, DELTA], ids=["hexapod", "delta"])
def test_law_equal_to_hertz_line_reproduces_it(path, tmp_path):
    base, law = _line_as_law(path, tmp_path)
    P = _random_poses(base, 8, 3)
    for joints in ("released", "rigid"):
        for backend in ("numpy", "compiled"):
            a = evaluate(base.device, P, WRENCH, joints=joints, backend=backend)
            b = evaluate(law.device, P, WRENCH, joints=joints, backend=backend)
            # an independent route to the same compliance (6 x 6 carried as a link vs the translational 3 x 3)
            assert _rel(b.K, a.K) < RTOL, (joints, backend)
            ia, ib = a.element_names.index("hertz_line"), b.element_names.index("measured_law")
            assert np.abs(b.element_energy[..., ib] - a.element_energy[..., ia]).max() \
                < RTOL * a.element_energy.sum(axis=-1).max(), (joints, backend)


def test_file_is_inlined_so_variants_keep_the_law(tmp_path):
    base, law = _line_as_law(HEXAPOD, tmp_path)
    assert "measured_law" in law.raw_json and "law_0_0.json" in law.raw_json   # the source path is recorded
    v = law.with_params(**{"legs.0.links.0.outer_diameter_m": 0.012})   # rebuilt from the document, not the file
    assert v.device.legs[0].measured_law.keys() == law.device.legs[0].measured_law.keys()
    np.testing.assert_array_equal(v.device.legs[0].measured_law[0][0], law.device.legs[0].measured_law[0][0])


def _backend_pairs(case, n_poses, pose_seed, rng):
    """(numpy result, compiled result, (joints, scaled)) at ``n_poses`` random poses under WRENCH, both joint
    idealizations, without and with random element scales in [0.5, 2] drawn from ``rng``."""
    dev = case.device
    P = _random_poses(case, n_poses, pose_seed)
    scale = rng.uniform(0.5, 2.0, (dev.n_legs, len(dev.element_names)))
    for joints in ("released", "rigid"):
        for es in (None, scale):
            yield (evaluate(dev, P, WRENCH, joints=joints, element_scale=es, backend="numpy"),
                   evaluate(dev, P, WRENCH, joints=joints, element_scale=es, backend="compiled"),
                   (joints, es is not None))


@pytest.fixture(scope="module")
def measured():
    return load_case(MEASURED)


def test_numpy_and_compiled_agree_on_the_fe_law(measured):
    for a, b, label in _backend_pairs(measured, 12, 5, np.random.default_rng(7)):
        for name in ("K", "S", "twist", "leg_wrench", "element_energy"):
            assert _rel(getattr(b, name), getattr(a, name)) < RTOL, label + (name,)


def test_beam_fe_reproduces_the_chain_model_with_the_fe_law(measured):
    # the beam FE takes the law as six springs on the eigen-twists of the 6 x 6: an independent route (1e-8 as
    # the other beam-FE checks; rounding of the condensation only)
    P = cube_points(measured)[[0, 3, 8]]
    for joints in ("released", "rigid"):
        r = evaluate(measured.device, P, WRENCH, joints=joints)
        K = device_fe_stiffness(measured.device, P, joints=joints, hertz_stiffness=r.hertz_stiffness)
        assert _rel(K, r.K) < 1e-8, joints


def _hexapod_with_law(S, frame=None):
    raw = _raw(HEXAPOD)
    for leg in raw["legs"]:
        j = leg["joints"][2]
        del j["hertz_point"]
        j["measured_law"] = {"compliance": np.asarray(S).tolist(), **({"frame": frame} if frame else {})}
    return build_case(raw, HEXAPOD)


def test_doubled_law_in_a_released_strut_adds_in_series():
    """A released U-P-S strut is a two-force member: its axial compliance is the sum of its elements' axial
    compliances, so doubling the S joint's law adds exactly the law's axial entry S_zz (any lateral or rotational
    entries, here the real contact-FE matrix, carry no load)."""
    S = np.array(json.loads(LAW.read_text())[0]["fe_compliance"], float)
    one, two = _hexapod_with_law(S), _hexapod_with_law(2.0 * S)
    P = _random_poses(one, 6, 11)
    r1 = evaluate(one.device, P, WRENCH, joints="released")
    r2 = evaluate(two.device, P, WRENCH, joints="released")
    for i in range(one.device.n_legs):
        u = r1.state.legs[i].C - r1.state.legs[i].centres[:, 0]
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        k1 = np.einsum("ni,nij,nj->n", u, r1.leg_stiffness[:, i, :3, :3], u)
        k2 = np.einsum("ni,nij,nj->n", u, r2.leg_stiffness[:, i, :3, :3], u)
        # springs in series: 1/k(2S) - 1/k(S) = S_zz; relative to the leg compliance 1/k (rounding only)
        np.testing.assert_allclose(1.0 / k2 - 1.0 / k1, S[2, 2], rtol=0, atol=RTOL / k1.min())


def test_stiffer_law_stiffens_the_device():
    S = np.array(json.loads(LAW.read_text())[0]["fe_compliance"], float)
    P = _random_poses(load_case(HEXAPOD), 4, 2)
    for joints in ("released", "rigid"):
        soft = evaluate(_hexapod_with_law(S).device, P, WRENCH, joints=joints).K
        stiff = evaluate(_hexapod_with_law(0.5 * S).device, P, WRENCH, joints=joints).K
        # K(stiff) - K(soft) is positive semidefinite (compliance order); eigenvalue rounding 1e-9 of |K|
        ev = np.linalg.eigvalsh(stiff - soft)
        assert ev.min() > -RTOL * np.abs(soft).max(), joints
        assert ev.max() > 1e-4 * np.abs(soft).max(), joints     # and it does change


def _bad(tmp_path, law: dict, files: dict | None = None, joint: int = 2):
    raw = _raw(HEXAPOD)
    j = raw["legs"][1]["joints"][joint]
    j.pop("hertz_point", None), j.pop("hertz_line", None)
    j["measured_law"] = law
    for name, text in (files or {}).items():
        (tmp_path / name).write_text(text)
    with pytest.raises(CaseError) as exc:
        build_case(raw, tmp_path / "bad.toml")
    msg = str(exc.value)
    assert "\n" not in msg
    return msg


def test_bad_input_names_leg_joint_and_key(tmp_path):
    good = np.diag([1e-6, 1e-6, 1e-6, 1.0, 1.0, 1.0])
    m = _bad(tmp_path, {"file": "missing.json"})
    assert "legs[1].joints[2].measured_law.file" in m and "leg 1 ('b'), joint 2 (S)" in m and "not found" in m
    m = _bad(tmp_path, {"file": "five.json"}, {"five.json": json.dumps({"fe_compliance": np.eye(5).tolist()})})
    assert "legs[1].joints[2].measured_law.file" in m and "shape (5, 5)" in m
    asym = good.copy()
    asym[0, 3] = 1e-3
    m = _bad(tmp_path, {"compliance": asym.tolist()})
    assert "legs[1].joints[2].measured_law.compliance" in m and "not symmetric" in m
    indef = good.copy()
    indef[0, 3] = indef[3, 0] = 1e-2   # |S_03| > sqrt(S_00 S_33) = 1e-3
    m = _bad(tmp_path, {"compliance": indef.tolist()})
    assert "legs[1].joints[2].measured_law.compliance" in m and "not positive definite" in m
    m = _bad(tmp_path, {"file": "two.json"}, {"two.json": json.dumps([{"joint": "spherical", "fe_compliance": good.tolist()},
                                                                      {"joint": "universal", "fe_compliance": good.tolist()}])})
    assert "legs[1].joints[2].measured_law.joint" in m and "2 entries" in m
    m = _bad(tmp_path, {"file": "nan.json"}, {"nan.json": json.dumps({"fe_compliance": [[None] * 6] * 6})})
    assert "legs[1].joints[2].measured_law.file" in m
    m = _bad(tmp_path, {"compliance": good.tolist(), "file": "x.json"})
    assert "legs[1].joints[2].measured_law" in m and "exactly one" in m
    m = _bad(tmp_path, {"compliance": good.tolist(), "frame": "link_after"})
    assert "legs[1].joints[2].measured_law.frame" in m and "no link after" in m
    m = _bad(tmp_path, {"compliance": good.tolist()}, joint=1)
    assert "legs[1].joints[1]" in m and "only on an R, U or S joint" in m


def test_cli_bad_law_is_one_line_and_exit_2(tmp_path, capsys):
    from femcheck.cli import main
    text = HEXAPOD.read_text()
    line = text.splitlines()[[k for k, s in enumerate(text.splitlines()) if "hertz_point" in s][0]]
    (tmp_path / "h.toml").write_text(text.replace(line, '  measured_law = { file = "laws/none.json" }', 1))
    assert main(["stiffness", str(tmp_path / "h.toml"), "--point", "P0"]) == 2
    err = capsys.readouterr().err.strip()
    assert "legs[0].joints[2].measured_law.file" in err and "not found" in err and len(err.splitlines()) == 1


def test_example_case_stiffness_runs():
    from femcheck.cli import get_app
    res = CliRunner().invoke(get_app(), ["stiffness", str(MEASURED), "--point", "P0"])
    assert res.exit_code == 0, res.output
    assert "measured_law" in res.output
    # docs/parallel_device.md quotes this run: its line is what the command prints now
    doc = " ".join((ROOT / "docs" / "parallel_device.md").read_text().split())
    line = next(ln for ln in res.output.splitlines() if ln.startswith("directional stiffness"))
    assert " ".join(line.split()) in doc


# ---------------------------------------------------------------- force ladder (load-dependent axial entry)
LADDER = ROOT / "cases" / "laws" / "haptic_6psu_spherical_ladder_coarse.json"


def test_hertz_ladder_reproduces_hertz_point():
    """A ladder sampled from the Hertz approach delta = (9 F^2 / (16 E*^2 R))^(1/3) is one power law (p = 2/3), so
    its tangent is the hertz_point tangent (6 E*^2 R F)^(1/3) exactly, and in a released hexapod (each ball loaded
    along its strut) the fixed points agree: K_T to 1e-9 (the fixed point stops at 1e-12)."""
    base = load_case(HEXAPOD)
    E, R, F_min = base.device.legs[0].hertz_point[2]
    F = np.geomspace(F_min, 200.0, 7)
    d = (9.0 * F ** 2 / (16.0 * E ** 2 * R)) ** (1.0 / 3.0)
    raw = _raw(HEXAPOD)
    for leg in raw["legs"]:
        j = leg["joints"][2]
        del j["hertz_point"]
        j["measured_law"] = {"compliance": np.diag([1e-6, 1e-6, 1e-6, 1.0, 1.0, 1.0]).tolist(),
                             "loads_N": F.tolist(), "approach_m": d.tolist()}
    law = build_case(raw, HEXAPOD)
    P = _random_poses(base, 6, 13)
    for W in (WRENCH, [0.0, 0.0, 60.0, 0.0, 0.0, 0.0], None):   # 60 N: beyond the floor in every leg
        for backend in ("numpy", "compiled"):
            a = evaluate(base.device, P, W, joints="released", backend=backend)
            b = evaluate(law.device, P, W, joints="released", backend=backend)
            assert _rel(b.K, a.K) < RTOL, backend
            for key, k in a.hertz_stiffness.items():
                np.testing.assert_allclose(b.hertz_stiffness[key], k, rtol=1e-9)


def test_ladder_file_beam_fe_and_backends(measured):
    # the ladder law written by femcheck.parallel.joint_law_file from the contact FE's force ladder
    raw = json.loads(measured.raw_json)
    for leg in raw["legs"]:
        leg["joints"][2]["measured_law"] = {"file": str(LADDER), "frame": "link_after"}
    case = build_case(raw, MEASURED)
    assert case.device.legs[0].measured_ladder   # the file's ladder was read
    P = cube_points(case)[[0, 3, 8]]
    for joints in ("released", "rigid"):
        r = evaluate(case.device, P, [0.0, 0.0, 15.0, 0.0, 0.0, 0.0], joints=joints, backend="numpy")
        K = device_fe_stiffness(case.device, P, joints=joints, hertz_stiffness=r.hertz_stiffness)
        assert _rel(K, r.K) < 1e-8, joints   # beam FE at the converged axial tangent (fixed point 1e-12, rounding)
    # a heavier load stiffens the ball (p < 1: tangent compliance falls with the force)
    lo = evaluate(case.device, P[:1], [0.0, 0.0, 5.0, 0.0, 0.0, 0.0], joints="released").hertz_stiffness
    hi = evaluate(case.device, P[:1], [0.0, 0.0, 50.0, 0.0, 0.0, 0.0], joints="released").hertz_stiffness
    assert all(hi[k][0] > lo[k][0] for k in lo)


def test_ladder_numpy_and_compiled_agree():
    """The kernel's ladder legs (refactored at every fixed-point iteration) against the numpy fixed point: the 6-PSU
    legs with the ladder ball law, and a hexapod with a ladder on the base U joint next to the Hertz ball of the
    same leg, random poses and element scales, both idealizations: 1e-9 (both stop the fixed point at 1e-12)."""
    raw = json.loads(load_case(MEASURED).raw_json)
    for leg in raw["legs"]:
        leg["joints"][2]["measured_law"] = {"file": str(LADDER), "frame": "link_after"}
    psu = build_case(raw, MEASURED)
    doc = json.loads(LADDER.read_text())
    raw = _raw(HEXAPOD)
    for leg in raw["legs"]:
        j = leg["joints"][0]
        del j["hertz_line"]
        j["measured_law"] = {k: doc[k] for k in ("loads_N", "approach_m")} | {"compliance": doc["fe_compliance"]}
    hexa = build_case(raw, HEXAPOD)
    rng = np.random.default_rng(17)
    for case in (psu, hexa):
        for a, b, label in _backend_pairs(case, 8, 19, rng):
            for name in ("K", "S", "twist", "leg_wrench", "element_energy"):
                assert _rel(getattr(b, name), getattr(a, name)) < RTOL, (case.meta.name,) + label + (name,)
            assert a.hertz_stiffness.keys() == b.hertz_stiffness.keys()
            for key in a.hertz_stiffness:
                np.testing.assert_allclose(b.hertz_stiffness[key], a.hertz_stiffness[key], rtol=RTOL)


def test_bad_ladder(tmp_path):
    good = np.diag([1e-6, 1e-6, 1e-6, 1.0, 1.0, 1.0]).tolist()
    m = _bad(tmp_path, {"compliance": good, "loads_N": [1.0, 2.0]})
    assert "legs[1].joints[2].measured_law.approach_m" in m
    m = _bad(tmp_path, {"compliance": good, "loads_N": [1.0, 2.0], "approach_m": [2e-6, 1e-6]})
    assert "legs[1].joints[2].measured_law.approach_m" in m and "growing" in m
    m = _bad(tmp_path, {"file": "lad.json"}, {"lad.json": json.dumps({"fe_compliance": good, "loads_N": [3.0, 1.0],
                                                                      "approach_m": [1e-6, 2e-6]})})
    assert "legs[1].joints[2].measured_law.file" in m and "increasing" in m
