"""Pose and rotation conversions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_manip import geometry as g


def test_yaw_round_trips_and_a_quarter_turn_turns_x_into_y() -> None:
    for yaw in (-3.0, -0.5, 0.0, 1.2, 3.1):
        assert g.yaw_of(g.quat_from_yaw(yaw)) == pytest.approx(yaw)
    r = g.rotation_matrix(g.quat_from_yaw(math.pi / 2))
    assert r @ np.array([1.0, 0.0, 0.0]) == pytest.approx([0.0, 1.0, 0.0])
    assert g.euler_from_quat(g.quat_from_euler((0.1, -0.2, 0.3))) == pytest.approx((0.1, -0.2, 0.3))


def test_matrix_and_row_are_inverse_conversions() -> None:
    quat = np.array(g.quat_from_euler((0.4, -0.7, 2.0)))
    row = np.concatenate([[1.0, -2.0, 0.5], quat])
    t = g.row_matrix(row)
    assert t[:3, 3] == pytest.approx([1.0, -2.0, 0.5])
    assert g.matrix_row(t) == pytest.approx(row if quat[3] >= 0 else np.r_[row[:3], -quat])
    assert g.pose_matrix(row[:3], 2.0 * quat) == pytest.approx(t)  # quaternions are normalised
    assert g.inverse_matrix(t) @ t == pytest.approx(np.eye(4))


def test_frames_and_poses_compose_like_their_matrices() -> None:
    a = ((0.3, 0.0, 1.0), g.quat_from_euler((0.0, 0.5, 1.0)))
    b = ((0.0, 2.0, -1.0), g.quat_from_euler((1.0, 0.0, -0.3)))
    expected = g.pose_matrix(*a) @ g.pose_matrix(*b)
    pos, quat = g.compose_poses(a, b)
    assert g.pose_matrix(pos, quat) == pytest.approx(expected, abs=1e-6)
    fa, fb = g.frame_of(*a), g.frame_of(*b)
    p, r = g.compose(fa, fb)
    assert p == pytest.approx(expected[:3, 3]) and r == pytest.approx(expected[:3, :3])
    back = g.compose(g.inverse(fa), fa)
    assert back[0] == pytest.approx(np.zeros(3), abs=1e-12) and back[1] == pytest.approx(np.eye(3))
    ipos, iquat = g.invert_pose(a)
    inverted = g.inverse_matrix(g.pose_matrix(*a))
    assert g.pose_matrix(ipos, iquat) == pytest.approx(inverted, abs=1e-6)


def test_urdf_rpy_matrix_agrees_with_the_simulator_convention() -> None:
    rpy = (0.3, -1.1, 2.4)
    assert g.rpy_matrix(*rpy) == pytest.approx(g.rotation_matrix(g.quat_from_euler(rpy)))
