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
    """A cable of half the modulus in leg 0 (and, in another world, in leg 2): at P5 under +-20 N along each axis,
    the change of the FE world's deflections points where the analytical chain's does when that leg's actuation,
    and no other leg's, is softened (cosine of the stacked 18-vectors > 0.99; the other legs' <= 0.87 here, so a
    change put on another leg fails). The chain is an independent model of the same device (released joints,
    which the frictional joints approach in slip)."""
    from femcheck.diagnose import AnalyticalChainModel
    soft = case.with_params(**{"actuation.cable_modulus_Pa": case.actuation.cable_modulus_Pa * 0.5})
    P = point_poses(case)[[5] * 6]
    F = 20.0 * np.vstack([np.eye(3), -np.eye(3)])
    nominal = _light(case).tcp_displacement(P, F)
    chain = AnalyticalChainModel(case, "detailed", "released")
    base = chain.tcp_displacement(P, F, chain.base_scale)
    per_leg = []
    for i in range(6):
        scale = np.array(chain.base_scale, float)
        scale[i, 1] *= 1.5   # element 1 = actuation (femcheck.chain.ELEMENTS)
        per_leg.append((chain.tcp_displacement(P, F, scale) - base).ravel())
    for leg in (0, 2):
        d = (_light(case, tuple(soft if i == leg else case for i in range(6))).tcp_displacement(P, F) - nominal).ravel()
        cos = np.array([d @ c / np.linalg.norm(d) / np.linalg.norm(c) for c in per_leg])
        assert cos[leg] > 0.99 and np.delete(cos, leg).max() < 0.9, cos


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
    """As above, on the device FE of ``verify`` (solid parts, actuation FE, the ball's contact-FE law and measured
    tilt slip ratio, coarse meshes) with the U joint's closed-form line contact and pin bending: the case's solid U
    joint has a 10 um pin play (``[solid.universal_joint] pin_clearance_m``), which its contact FE takes up below
    0.5 N, so with its law the world would hold a clearance (the positive control below). A line-to-line pin cannot
    be measured by that contact FE here (no clearance: every bore point is kept, > 8 GB; 1 um: below the facet
    chord error of its mesh, 2.4 um)."""
    d = _fe_world_diagnosis(case, DeviceFEWorld.of(case, joint_fe=("spherical",)), seed=12)
    assert "clearance" not in {c.id for c in d.causes}, [c.id for c in d.causes]


@pytest.mark.slow
def test_contact_fe_world_with_pin_play_is_named_clearance(case):
    """Positive control of the test above: the same device FE with the U joint's contact-FE law too, whose pins
    have the case's default 10 um play (taken up below 0.5 N: its approach starts at 2c), is named ``clearance``,
    needed beyond friction, Hertz stiffening and the joints' rotation release (measured: gaps 26-56 um at the TCP
    closed at 0.2 N, held-out chi2 gain 5328 against the threshold 78)."""
    d = _fe_world_diagnosis(case, DeviceFEWorld.of(case), seed=12)
    assert "clearance" in {c.id for c in d.causes}, [c.id for c in d.causes]
    assert d.as_json()["clearance_check"]["needed"]


def test_anchored_chain_reads_the_case_fe_and_names_nothing_on_it(case):
    """The chain anchored on the unchanged case's device FE reads that FE at the nominal parameters (at the gap
    table's load levels exactly: the readings' 5/20 N and the sweep; between levels the gap is linear in the load,
    here within 2 % of the deflection at 3.7 N), and diagnosing the unchanged FE world through it names no cause
    (through the plain rigid chain such readings are named joint_rotation_release and spherical_joint_in_legs)."""
    from femcheck.diagnose import diagnose
    from femcheck.diagnose.fe_model import FEAnchoredChainModel
    from femcheck.experiment.dial_gauge import dial_campaign
    from femcheck.measured import process
    world = _light(case)
    r = process(dial_campaign(case, {"device": world}, seed=13, directions=BOTH_SIGNS).data, case)
    tot = r.total_state
    model = FEAnchoredChainModel.nearest(case, _light(case), r.pose[tot], r.force[tot])
    assert model.joints == "released"   # frictional joints slip at the test loads
    P = point_poses(case)[[5, 5, 5]]
    F = np.array([[20.0, 0, 0], [0, -5.0, 0], [0, 0, 3.7]])
    got = model.tcp_displacement(P, F, model.base_scale)
    want = world.tcp_displacement(P, F)
    np.testing.assert_allclose(got[:2], want[:2], rtol=1e-12, atol=1e-15)
    assert np.linalg.norm(got[2] - want[2]) < 0.02 * np.linalg.norm(want[2])
    d = diagnose(model, r, with_baseline=False)
    assert [c.id for c in d.causes if c.id != "none"] == [], [c.id for c in d.causes]
