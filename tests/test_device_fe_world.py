"""The device-FE world of changed legs, and a frictional contact-joint FE world that has no clearance.

Light tests use beam parts and the closed-form joint springs (frictional ``contact`` joints still: stick and slip
of the ball and the pins, Hertz secants); the slow ones the solid parts and the joints' contact-FE laws.
"""
import numpy as np
import pytest

from femcheck.experiment.device_fe_world import DeviceFEWorld, LegJointLaws
from femcheck.kinematics.psu6 import test_points as point_poses

#: both signs of each axis, as the physical-worlds bench reads them
BOTH_SIGNS = ("+x", "+y", "+z", "-x", "-y", "-z")


def _light(case, legs=None):
    return DeviceFEWorld(case, legs or (case,) * 6, kind="beam", joint_fe=False, tilt_slip_ratio=1.0)


def test_unchanged_world_is_the_device_fe_of_verify(case):
    """Every leg the case: the world reads what the device FE of ``verify`` reads (``run_fe`` and its reading model,
    same beam parts, closed-form frictional joints). Both solve the same equations with the same inputs, so they
    agree to round-off (1e-12 relative); the check guards the leg-by-leg assembly of parts, cables and friction."""
    from femcheck.diagnose.fe_model import DeviceFEReadingModel
    from femcheck.verify.fe import run_fe
    fe = run_fe(case, ("P0", "P5"), ("detailed",), "coarse", kind="beam")
    ref = DeviceFEReadingModel(case, fe)
    P = point_poses(case)
    pose = P[[0, 0, 0, 5, 5, 5]]
    force = np.array([[5, 0, 0], [20, 0, 0], [0, 0, -20], [0, 20, 0], [-20, 0, 0], [0, 0, 20.0]])
    got = _light(case).tcp_displacement(pose, force)
    want = ref.tcp_displacement(pose, force, ref.base_scale)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


def test_a_changed_leg_acts_where_it_is(case):
    """A softer cable in leg 0 and, in another world, in leg 2 (the base pair 120 deg further on): at P0 (on the
    device's 3-fold axis) the second world under the load rotated by 120 deg deflects as the first one rotated by
    120 deg. Exact for the symmetric device (beam parts, to 1e-9 relative: the solve's fixed-point tolerance);
    with the change put on the wrong leg, or on all legs, the rotated deflections differ by the change itself."""
    soft = case.with_params(**{"actuation.cable_modulus_Pa": case.actuation.cable_modulus_Pa * 0.5})
    c, s = np.cos(2 * np.pi / 3), np.sin(2 * np.pi / 3)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    P0 = point_poses(case)[[0, 0, 0]]
    F = np.array([[20.0, 0, 0], [3.0, 20.0, -4.0], [0, 5.0, 20.0]])
    legs0 = tuple(soft if i == 0 else case for i in range(6))
    legs2 = tuple(soft if i == 2 else case for i in range(6))
    d0 = _light(case, legs0).tcp_displacement(P0, F)
    d2 = _light(case, legs2).tcp_displacement(P0, F @ R.T)
    nominal = _light(case).tcp_displacement(P0, F)
    assert np.abs(d0 - nominal).max() > 0.02 * np.abs(nominal).max()   # the change shows
    np.testing.assert_allclose(d2, d0 @ R.T, rtol=0, atol=1e-9 * np.abs(d0).max())


def test_leg_joint_laws_answer_per_leg():
    """Six legs' laws read as one: leg i's secant and stiffness are its own law's at its own force."""
    from femcheck.fe_device.joint_laws import MeasuredJointLaw
    F = np.geomspace(0.5, 25.0, 5)
    K = np.tile(np.diag([1e6, 1e6, 2e6, 50.0, 50.0, 20.0]), (5, 1, 1))
    a = MeasuredJointLaw("universal", "coarse", F, 1e-6 * (F / F[0]) ** (2 / 3), K, 1, 1, 0.0)
    b = MeasuredJointLaw("universal", "coarse", F, 2e-6 * (F / F[0]) ** 0.6, 3.0 * K, 1, 1, 0.0)
    laws = LegJointLaws((a, a, b, a, a, a))
    f = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    want = np.array([(b if i == 2 else a).secant(f[i]) for i in range(6)])
    np.testing.assert_array_equal(laws.secant(f), want)
    np.testing.assert_array_equal(laws.component_stiffness(f)[2], b.component_stiffness(f[2]))


def _fe_world_diagnosis(case, world, seed):
    from femcheck.diagnose import AnalyticalChainModel, diagnose
    from femcheck.experiment.dial_gauge import dial_campaign
    from femcheck.measured import process
    r = process(dial_campaign(case, {"device": world}, seed=seed, directions=BOTH_SIGNS).data, case)
    return diagnose(AnalyticalChainModel(case, "detailed", case.model.joint_rotations), r, with_baseline=False)


def test_frictional_contact_fe_world_is_not_named_clearance(case):
    """The device FE with frictional contact joints (stick, then slip at μ F r; Hertz secants) and no clearance,
    read by dial gauges, diagnosed against the case's analytical chain: the joints' stick/slip and Hertz
    nonlinearity are not a dead band, so ``clearance`` is not named (light variant: beam parts, closed-form joint
    springs)."""
    d = _fe_world_diagnosis(case, _light(case), seed=11)
    assert "clearance" not in {c.id for c in d.causes}, [c.id for c in d.causes]


@pytest.mark.slow
def test_contact_fe_world_is_not_named_clearance(case):
    """As above, on the device FE of ``verify``: solid parts, actuation FE, the joints' contact-FE laws and the
    measured tilt slip ratio (coarse meshes)."""
    d = _fe_world_diagnosis(case, DeviceFEWorld.of(case), seed=12)
    assert "clearance" not in {c.id for c in d.causes}, [c.id for c in d.causes]
