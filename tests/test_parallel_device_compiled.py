"""The compiled (numba) path of the general parallel-device model against its numpy reference:
same equations, so the two agree to rounding on random poses of the three reference devices; the closed-form
inverse kinematics (F-P-S-U, U-P-S and R-U-U legs) against the numeric one."""
from __future__ import annotations

import numpy as np
import pytest

from femcheck.case import load_case
from femcheck.parallel.chain_model import evaluate
from femcheck.parallel.compiled import solve_legs_compiled
from femcheck.parallel.device import test_points as cube_points
from femcheck.parallel.kernel_tables import IK_NUMERIC, IK_PSU, IK_RUU, IK_UPS, device_tables
from femcheck.parallel.leg_kinematics import solve_legs
from tests.conftest import ROOT

#: the issue's bar. Both paths evaluate the same equations in a different order (and the numeric IK stops at
#: a residual of 1e-11 m, the closed form at rounding), so they differ by ~1e-12 (measured 2e-16..4e-12)
RTOL = 1e-9
#: joint values: the numeric IK stops at |e| < 1e-11 (m, rad) and the joint values follow with the
#: conditioning of the leg Jacobian (measured 2e-13)
Q_TOL = 1e-9
DEVICES = ("hexapod_6ups", "delta_3ruu", "haptic_6psu")


@pytest.fixture(scope="module", params=DEVICES)
def device_case(request):
    return request.param, load_case(ROOT / "cases" / f"{request.param}.toml")


def _poses(name, case, n=25, seed=3):
    rng = np.random.default_rng(seed)
    P = np.tile(cube_points(case)[0], (n, 1))
    P[:, :3] += rng.uniform(-0.02, 0.02, (n, 3))
    if name != "delta_3ruu":  # the Delta is translational: its platform stays at rotation 0
        P[:, 3:] += rng.uniform(-0.05, 0.05, (n, 3))
    return np.vstack([cube_points(case), P])


def _rel(a, b):
    return np.abs(a - b).max() / np.abs(a).max()


@pytest.mark.parametrize("joints", ["rigid", "released"])
def test_compiled_model_reproduces_the_numpy_model(device_case, joints):
    name, case = device_case
    dev = case.device
    P = _poses(name, case)
    state_np = solve_legs(dev, P, backend="numpy")
    scale = np.random.default_rng(5).uniform(0.5, 2.0, (dev.n_legs, len(dev.element_names)))
    for model in ("simplified", "detailed"):
        for wrench, element_scale in ((None, None), ([6.0, -4.0, 10.0, 0.1, -0.05, 0.02], None),
                                      ([0.0, 0.0, 10.0, 0.0, 0.0, 0.0], scale)):
            a = evaluate(dev, P, wrench, model=model, joints=joints, state=state_np, element_scale=element_scale,
                         backend="numpy")
            b = evaluate(dev, P, wrench, model=model, joints=joints, element_scale=element_scale)  # compiled IK too
            assert _rel(a.K, b.K) < RTOL
            assert _rel(a.S, b.S) < RTOL
            assert _rel(a.leg_stiffness, b.leg_stiffness) < RTOL
            assert set(a.hertz_stiffness) == set(b.hertz_stiffness)
            for key, k in a.hertz_stiffness.items():
                assert _rel(k, b.hertz_stiffness[key]) < RTOL
            if wrench is not None:
                assert _rel(a.twist, b.twist) < RTOL
                assert _rel(a.leg_wrench, b.leg_wrench) < RTOL
                assert _rel(a.element_energy, b.element_energy) < RTOL
                assert np.allclose(a.contributions, b.contributions, rtol=0, atol=RTOL)


def test_closed_form_ik_agrees_with_the_numeric_ik(device_case):
    name, case = device_case
    dev = case.device
    expected = {"hexapod_6ups": IK_UPS, "haptic_6psu": IK_PSU, "delta_3ruu": IK_RUU}[name]
    assert (device_tables(dev).ik_kind == expected).all()
    P = _poses(name, case, n=100, seed=8)
    fast = solve_legs(dev, P)                                   # closed forms where the legs have one
    numeric = solve_legs_compiled(dev, P, numeric_only=True)    # compiled Gauss-Newton
    ref = solve_legs(dev, P, backend="numpy")                   # numpy Gauss-Newton
    assert fast.packed[5].all() == (expected != IK_NUMERIC) and not numeric.packed[5].any()
    assert fast.ok.all() and numeric.ok.all() and ref.ok.all()
    for a, b, c in zip(fast.legs, numeric.legs, ref.legs):
        for other in (b, c):
            assert np.abs(a.q - other.q).max() < Q_TOL
            assert np.abs(a.C - other.C).max() < Q_TOL          # m; the attachment is given, so this is the residual
            assert np.abs(a.centres - other.centres).max() < Q_TOL
            assert np.abs(a.twists - other.twists).max() < Q_TOL
            assert np.abs(a.link_R - other.link_R).max() < Q_TOL
            assert np.abs(a.link_length - other.link_length).max() < Q_TOL


@pytest.mark.parametrize("name", ["hexapod_6ups", "haptic_6psu", "delta_3ruu"])
def test_closed_form_reports_unreachable_poses_like_the_numeric_ik(name):
    """Far outside the workspace the closed form has no real solution or violates a joint limit: both paths say
    the leg cannot reach the pose."""
    case = load_case(ROOT / "cases" / f"{name}.toml")
    P = np.tile(cube_points(case)[0], (3, 1))
    P[0, 2] += 0.5    # far above
    P[1, 0] += 0.4    # far to the side
    a, b = solve_legs(case.device, P), solve_legs(case.device, P, backend="numpy")
    assert not a.ok[:2].any() and not b.ok[:2].any()
    assert a.ok[2] and b.ok[2]
    for sa, sb in zip(a.legs, b.legs):
        assert (sa.ok == sb.ok).all()


def test_delta_closed_form_ik_matches_the_numeric_ik_to_rounding():
    """The Delta's R*-U-U closed form (crank from the elbow circle meeting the rod sphere, then subproblems 2 and 1)
    against the compiled Gauss-Newton on random reachable poses of a 60 mm cube around P0 (wider than the test
    cube): the numeric IK stops at |e| < 1e-13 and the joint values follow with the leg's conditioning, so they
    agree to ~1e-12 (measured 1.3e-12 over 400 such poses) and K_T to ~1e-12 relative (measured 1.0e-12 rigid,
    3.3e-12 released: the released wrench basis comes from the passive twists). A pose with a platform rotation,
    which the translational legs cannot follow, and poses out of reach fall back to the numeric solution and are
    refused alike."""
    case = load_case(ROOT / "cases" / "delta_3ruu.toml")
    dev = case.device
    rng = np.random.default_rng(21)
    P = np.tile(cube_points(case)[0], (200, 1))
    P[:, :3] += rng.uniform(-0.03, 0.03, (200, 3))
    fast, numeric = solve_legs(dev, P), solve_legs_compiled(dev, P, numeric_only=True)
    assert fast.packed[5].all() and fast.ok.all() and numeric.ok.all()
    for a, b in zip(fast.legs, numeric.legs):
        assert np.abs(a.q - b.q).max() < 1e-11
    for joints in ("rigid", "released"):
        K_fast = evaluate(dev, P, [0, 0, 10, 0, 0, 0], joints=joints).K
        K_num = evaluate(dev, P, [0, 0, 10, 0, 0, 0], joints=joints, state=numeric).K
        assert _rel(K_num, K_fast) < 1e-11
    Q = np.tile(cube_points(case)[0], (4, 1))
    Q[0, 2] += 0.5     # above the base: out of reach
    Q[1, 0] += 0.4     # far to the side
    Q[3, 3] += 0.1     # a platform rotation: the closed form's orientation misses, the numeric IK cannot close it
    a, b = solve_legs(dev, Q), solve_legs_compiled(dev, Q, numeric_only=True)
    assert not a.packed[5][:, 0].any() and not a.packed[5][:, 3].all()
    for sa, sb in zip(a.legs, b.legs):
        assert (sa.ok == sb.ok).all()
    assert a.ok.tolist() == [False, False, True, False]


def test_unknown_backend_is_refused(device_case):
    _, case = device_case
    with pytest.raises(ValueError, match="backend"):
        evaluate(case.device, cube_points(case), backend="fortran")


def test_redundant_legs_take_the_numeric_ik_and_the_numpy_released_model(tmp_path):
    """S-P-S struts (the hexapod with its base U joints made S): 7 freedoms per leg, the spin about the strut is
    redundant, so the passive twists are dependent. The compiled IK takes the numeric (redundant) step and the
    released model falls back to numpy; both still agree with the numpy path to rounding."""
    text = (ROOT / "cases" / "hexapod_6ups.toml").read_text().replace('type = "U"', 'type = "S"')
    text = "\n".join(line for line in text.splitlines() if not line.strip().startswith("hertz_line"))
    (tmp_path / "sps.toml").write_text(text)
    case = load_case(tmp_path / "sps.toml")
    dev = case.device
    tb = device_tables(dev)
    assert not tb.released_ok and (tb.ik_kind == IK_NUMERIC).all()
    P = _poses("sps", case, n=10)
    a, b = solve_legs(dev, P), solve_legs(dev, P, backend="numpy")
    assert a.ok.all() and b.ok.all()
    for sa, sb in zip(a.legs, b.legs):
        assert np.abs(sa.C - sb.C).max() < Q_TOL
    for joints in ("rigid", "released"):
        r1 = evaluate(dev, P, [1.0, 2.0, 10.0, 0.0, 0.0, 0.0], joints=joints)
        r2 = evaluate(dev, P, [1.0, 2.0, 10.0, 0.0, 0.0, 0.0], joints=joints, state=b, backend="numpy")
        assert _rel(r2.K, r1.K) < RTOL


@pytest.mark.parametrize("joints", ["rigid", "released"])
def test_fused_path_matches_the_solved_state_path(device_case, joints):
    """evaluate without a state runs the inverse kinematics and the chain model in one compiled call
    (evaluate_kernel); with a state, the chain kernel alone. Same equations in the same order, so they agree to
    rounding (measured: identical); its state, solved on first use, is the compiled inverse kinematics."""
    name, case = device_case
    dev = case.device
    P = _poses(name, case)
    W = [6.0, -4.0, 10.0, 0.1, -0.05, 0.02]
    for model in ("simplified", "detailed"):
        a = evaluate(dev, P, W, model=model, joints=joints)
        b = evaluate(dev, P, W, model=model, joints=joints, state=solve_legs(dev, P))
        for x, y in ((a.K, b.K), (a.S, b.S), (a.twist, b.twist), (a.leg_stiffness, b.leg_stiffness),
                     (a.leg_wrench, b.leg_wrench), (a.element_energy, b.element_energy)):
            assert _rel(y, x) < 1e-12
        assert np.allclose(a.contributions, b.contributions, rtol=0, atol=1e-12)
        assert a.iterations == b.iterations
        for sa, sb in zip(a.state.legs, solve_legs(dev, P).legs):
            assert np.array_equal(sa.q, sb.q) and np.array_equal(sa.twists, sb.twists)


@pytest.mark.parametrize("name", DEVICES)
def test_fused_path_reports_an_unreachable_pose_like_the_state_path(name):
    from femcheck.errors import UnreachablePoseError
    case = load_case(ROOT / "cases" / f"{name}.toml")
    P = np.tile(cube_points(case)[0], (3, 1))
    P[1, 2] += 0.5    # far above: no leg reaches it
    with pytest.raises(UnreachablePoseError) as fused:
        evaluate(case.device, P)
    with pytest.raises(UnreachablePoseError) as solved:
        evaluate(case.device, P, state=solve_legs(case.device, P))
    assert str(fused.value) == str(solved.value) and "#1 " in str(fused.value)


def test_fused_path_checks_a_limit_on_a_passive_joint():
    """The fused closed form skips the passive joint angles unless a joint limit needs them. Case files limit only
    R and P joints (in the closed-form legs, the actuated P), so the limit is put on the hexapod's base U joint
    (its first angle) in the device object, at the median of its range over rotated poses, so that some poses
    exceed it. Both paths must refuse the same first pose and agree on the others."""
    import dataclasses

    from femcheck.errors import UnreachablePoseError
    dev0 = load_case(ROOT / "cases" / "hexapod_6ups.toml").device
    case = load_case(ROOT / "cases" / "hexapod_6ups.toml")
    rng = np.random.default_rng(11)
    P = np.tile(cube_points(case)[0], (40, 1))
    P[:, 3:] += rng.uniform(-0.4, 0.4, (40, 3))
    free = solve_legs(dev0, P)
    assert free.ok.all()
    lim = float(np.median([np.abs(s.q[:, 0]).max() for s in free.legs]))
    dev = dataclasses.replace(dev0, legs=tuple(dataclasses.replace(leg, limits=leg.limits + ((0, -lim, lim),))
                                               for leg in dev0.legs))
    assert (device_tables(dev).tab[0][:, 8] == 1).all() and (device_tables(dev).ik_kind == IK_UPS).all()
    state = solve_legs(dev, P)
    assert not state.ok.all() and state.ok.any()
    with pytest.raises(UnreachablePoseError) as fused:
        evaluate(dev, P)
    with pytest.raises(UnreachablePoseError) as solved:
        evaluate(dev, P, state=state)
    assert str(fused.value) == str(solved.value)
    ok = P[state.ok]
    a, b = evaluate(dev, ok, [0, 0, 10, 0, 0, 0]), evaluate(dev, ok, [0, 0, 10, 0, 0, 0], state=solve_legs(dev, ok))
    assert _rel(b.K, a.K) < 1e-12


_VARIANT_SCRIPT = """
import json
from femcheck.parallel.precompile import compile_kernels
print(json.dumps(compile_kernels()))
"""


@pytest.mark.slow
def test_every_kernel_function_compiles_one_specialization(tmp_path):
    # numba compiles a function once per distinct argument typing (array layout C/A, ndim, readonly, and
    # literal constants from a jitted caller); each variant adds to the ~1 min cold first compile of the kernel.
    # With an empty cache (a cached load records no helper signatures) every function of the module must have
    # compiled at most once after the three reference devices ran in both joint idealizations.
    import json
    import os
    import subprocess
    import sys
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), PYTHONPATH=str(ROOT))
    env.pop("NUMBA_DISABLE_JIT", None)
    run = subprocess.run([sys.executable, "-c", _VARIANT_SCRIPT], cwd=ROOT, env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    counts = json.loads(run.stdout.strip().splitlines()[-1])
    assert counts["evaluate_kernel"] == 1, counts   # the check ran the compiled path
    # _ik_range: the full-state inverse kinematics (ik_kernel) and the fused kernel's reduced one are two
    # specializations on purpose: the fused one's constant flags drop the full-state branches (measured ~8% more
    # released poses/s, at the same cold compile time as one flag-generic specialization)
    assert counts["_ik_range"] <= 2, counts
    assert {k: c for k, c in counts.items() if c > 1 and k != "_ik_range"} == {}
