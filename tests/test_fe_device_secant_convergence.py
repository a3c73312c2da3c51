"""The device FE's secant fixed point converges where a slipping rotation spring makes the plain iteration crawl."""
import numpy as np
import pytest

from femcheck.errors import ConvergenceError
from femcheck.fe_device import loads


def _soft_tube_world(case):
    """Glass-fibre polyamide tubes (10 GPa) and a 13.7 % thinner guideway section in all six legs, beam parts and
    closed-form joint springs (seconds): a world in which a pin axis of the frictional U joint slips and carries most
    of the compliance of its rotation path, so the plain secant iteration contracts by ~0.92 per step."""
    from femcheck.bench.physical_worlds import changed_case
    from femcheck.experiment.device_fe_world import DeviceFEWorld
    changed = {**changed_case(case, "proximal_link_modulus", 0.0, "PA66_GF30"),
               **changed_case(case, "guideway_section", 0.8634)}
    return DeviceFEWorld(case, (case.with_params(**changed),) * 6, kind="beam", joint_fe=False, tilt_slip_ratio=1.0)


def test_slow_secant_fixed_point_converges_to_the_plain_iterations_limit(case, monkeypatch):
    """At P5 under the 5 N preload along +x the plain iteration does not reach 1e-10 in 200 steps (reproduces the
    failure); the safeguarded Aitken steps reach it, at the same fixed point as 5000 plain steps (rtol 1e-8: both
    stop at a relative change of 1e-10 of the springs, the deflection moves less)."""
    from femcheck.kinematics.psu6 import test_points
    world = _soft_tube_world(case)
    pose, force = test_points(case)[5:6], np.array([[5.0, 0.0, 0.0]])
    fast = world.tcp_displacement(pose, force)
    monkeypatch.setattr(loads, "ACCEL_AFTER", 10**9)   # plain iteration only
    with pytest.raises(ConvergenceError, match="did not converge in 200 iterations"):
        world.tcp_displacement(pose, force)
    monkeypatch.setattr(loads, "MAX_ITERATIONS", 5000)
    plain = world.tcp_displacement(pose, force)
    np.testing.assert_allclose(fast, plain, rtol=1e-8)
    assert abs(fast[0, 0]) > 1e-6   # a real deflection (µm), not a trivial zero


def test_aitken_step_only_for_slow_monotone_convergence(monkeypatch):
    """x_{n+1} = 0.92 x_n + 0.08 (fixed point 1): after the plain steps one extrapolation lands on the fixed point
    (exact for a linear map, rtol 1e-12); an alternating map (ratio -0.5) and a fast one (ratio 0.2) are left to
    the plain iteration (returned unchanged)."""
    monkeypatch.setattr(loads, "ACCEL_AFTER", 3)
    for ratio, jumps in ((0.92, True), (-0.5, False), (0.2, False)):
        acc, x = loads._AitkenSecant(), np.array([3.0, 5.0])
        for _ in range(6):
            new = ratio * x + (1.0 - ratio)
            out = acc(x, new)
            if acc.extrapolations:
                break
            assert np.array_equal(out, new)
            x = new
        assert bool(acc.extrapolations) == jumps
        if jumps:
            np.testing.assert_allclose(out, 1.0, rtol=1e-12)


def test_jumps_wait_after_a_jump_that_did_not_shrink_the_step(monkeypatch):
    """A jump on x_{n+1} = 0.92 x_n + 0.08, then a plain step larger than the one before the jump (a map that is not
    one linear mode there): the next ACCEL_AFTER (3) steps stay plain although they are slow and monotone, then the
    jumps resume; a jump followed by a smaller step does not wait (next jump two steps later)."""
    monkeypatch.setattr(loads, "ACCEL_AFTER", 3)
    for worse, plain_steps in ((True, 3), (False, 1)):
        acc, x = loads._AitkenSecant(), np.array([3.0, 5.0])
        while not acc.extrapolations:
            before = 0.08 * (x - 1.0)
            x = acc(x, 0.92 * x + 0.08)
        step = 2.0 * before if worse else 0.1 * before   # the plain step after the jump, larger or smaller
        x = acc(x, x - step)
        plain = 0
        while acc.extrapolations == 1 and plain < 10:   # slow monotone steps again (fixed point 7.25)
            new = 0.92 * x + 0.58
            out = acc(x, new)
            plain += np.array_equal(out, new)
            x = out
        assert acc.extrapolations == 2 and plain == plain_steps
