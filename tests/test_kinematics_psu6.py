"""6-PSU inverse/forward kinematics, test points and Jacobian (docs/conventions.md §2-3, §8)."""
from __future__ import annotations

import numpy as np
import pytest

from femcheck.errors import UnreachablePoseError
from femcheck.kinematics import psu6


def test_test_points_follow_the_reference_numbering(case, points):
    assert points.shape == (9, 6)
    assert points[0, :3] == pytest.approx([0, 0, 0.375])
    signs = np.sign(points[1:, :3] - points[0, :3])
    assert signs.tolist() == [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                              [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]]
    assert np.abs(points[1:, :3] - points[0, :3]) == pytest.approx(np.full((8, 3), 0.025))


def test_ik_closes_the_links_and_matches_reference_slider_range(case, points):
    legs = psu6.leg_geometry(case, points)
    # closure |C - B| = L2 to round-off
    assert np.abs(psu6.forward_residual(case, legs)).max() < 1e-14
    # reference: slider s 162-260 mm over the cube (quoted to 1 mm)
    assert legs.slider.min() == pytest.approx(0.162, abs=1e-3)
    assert legs.slider.max() == pytest.approx(0.260, abs=1e-3)


def test_ik_forward_round_trip(case):
    rng = np.random.default_rng(3)
    poses = np.tile(psu6.test_points(case)[0], (50, 1))
    poses[:, :3] += rng.uniform(-0.025, 0.025, (50, 3))
    poses[:, 3:] = rng.uniform(-0.05, 0.05, (50, 3))
    legs = psu6.leg_geometry(case, poses)
    back = psu6.forward_kinematics(case, legs.slider, psu6.test_points(case)[0])
    # Newton on a smooth map converges to round-off (1e-12 m on 0.4 m positions)
    assert np.abs(back - poses).max() < 1e-12


def test_jacobian_matches_finite_differences(case):
    pose = psu6.test_points(case)[3]
    legs = psu6.leg_geometry(case, pose)
    J = psu6.jacobian(case, legs)[0]
    h = 1e-7
    num = np.empty((6, 6))
    for k in range(6):
        dp = np.zeros(6)
        dp[k] = h
        # translation: plain finite difference; rotation: left-multiplied small rotation (omega)
        plus, minus = pose.copy(), pose.copy()
        if k < 3:
            plus[k] += h
            minus[k] -= h
        else:
            from femcheck.kinematics.frames import matrix_to_rotvec, rotvec_to_matrix
            R = rotvec_to_matrix(pose[3:])
            plus[3:] = matrix_to_rotvec(rotvec_to_matrix(dp[3:]) @ R)
            minus[3:] = matrix_to_rotvec(rotvec_to_matrix(-dp[3:]) @ R)
        num[:, k] = (psu6.leg_geometry(case, plus).slider[0] - psu6.leg_geometry(case, minus).slider[0]) / (2 * h)
    # central differences with h = 1e-7 m: truncation ~h^2, round-off ~1e-16/h -> 1e-7 relative
    assert np.abs(num - J).max() < 1e-6 * np.abs(J).max()


def test_condition_numbers_match_reference(case, points):
    cond = psu6.condition_number(case, psu6.leg_geometry(case, points))
    # reference values quoted to 4 significant digits: P0 3.767, P1/P4/P5/P8 4.100, P2/P3/P6/P7 4.278
    ref = [3.767, 4.100, 4.278, 4.278, 4.100, 4.100, 4.278, 4.278, 4.100]
    assert cond == pytest.approx(ref, abs=6e-4)


def test_unreachable_pose_names_pose_and_leg(case):
    pose = psu6.test_points(case)[0].copy()
    pose[2] = 0.60   # far above: sliders beyond the rail
    with pytest.raises(UnreachablePoseError) as err:
        psu6.leg_geometry(case, pose[None], labels=["lifted"])
    assert "lifted" in str(err.value) and "leg) 0" in str(err.value) and "outside" in str(err.value)
    pose[:3] = [0.4, 0.0, 0.375]  # too far sideways: links cannot reach
    with pytest.raises(UnreachablePoseError, match="cannot span"):
        psu6.leg_geometry(case, pose[None], labels=["sideways"])
