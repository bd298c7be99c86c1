"""Grasp frames computed from an object's box (the top grasp)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_manip.geometry import pose_matrix, quat_from_euler
from bt_manip.manipulation.grasps import GRASP_DEPTH, GraspError, top_grasp

PANEL = (1.2, 0.02, 0.15)


def _frame(xyz: tuple[float, float, float], rpy: tuple[float, float, float]) -> np.ndarray:
    return pose_matrix(xyz, quat_from_euler(rpy))


def _is_rotation(r: np.ndarray) -> bool:
    return bool(np.allclose(r.T @ r, np.eye(3), atol=1e-9) and np.isclose(np.linalg.det(r), 1.0))


@pytest.mark.parametrize("yaw", [0.0, 0.5236, -1.22693, 2.8])
def test_top_grasp_of_an_upright_panel_closes_across_its_thickness(yaw: float) -> None:
    pose = _frame((1.0, -2.0, 0.075), (0.0, 0.0, yaw))
    g = top_grasp(PANEL, pose, side=(0.0, 1.0), max_opening=0.1)
    assert _is_rotation(g[:3, :3])
    np.testing.assert_allclose(g[:3, 2], [0.0, 0.0, -1.0], atol=1e-9)  # from above
    thickness_axis = pose[:3, 1]  # the panel's 2 cm side
    assert abs(float(g[:3, 1] @ thickness_axis)) == pytest.approx(1.0)
    assert abs(float(g[:3, 0] @ pose[:3, 0])) == pytest.approx(1.0)  # x along the panel
    assert float(g[:2, 0] @ np.array([0.0, 1.0])) >= 0.0
    # the middle of the top edge, GRASP_DEPTH below it
    np.testing.assert_allclose(g[:3, 3], [1.0, -2.0, 0.15 - GRASP_DEPTH], atol=1e-9)


def test_the_side_picks_one_of_the_two_frames_half_a_turn_apart() -> None:
    pose = _frame((0.0, 0.0, 0.075), (0.0, 0.0, 0.3))
    left = top_grasp(PANEL, pose, side=(0.0, 1.0))
    right = top_grasp(PANEL, pose, side=(0.0, -1.0))
    np.testing.assert_allclose(right[:3, 0], -left[:3, 0], atol=1e-12)
    np.testing.assert_allclose(right[:3, 1], -left[:3, 1], atol=1e-12)
    np.testing.assert_allclose(right[:3, 2:], left[:3, 2:], atol=1e-12)


def test_a_leaning_panel_is_approached_along_its_own_up_axis() -> None:
    lean = math.radians(20)
    pose = _frame((0.0, 0.0, 0.07), (lean, 0.0, 0.0))  # turned about its long side
    g = top_grasp(PANEL, pose)
    up = pose[:3, 2]
    np.testing.assert_allclose(g[:3, 2], -up, atol=1e-9)
    np.testing.assert_allclose(g[:3, 3], pose[:3, 3] + up * (0.075 - GRASP_DEPTH), atol=1e-9)
    assert abs(float(g[:3, 1] @ pose[:3, 1])) == pytest.approx(1.0)


def test_a_box_on_its_side_is_taken_by_the_face_now_on_top() -> None:
    size = (0.3, 0.04, 0.06)
    pose = _frame((0.0, 0.0, 0.02), (math.pi / 2, 0.0, 0.0))  # local y points up
    g = top_grasp(size, pose, max_opening=0.1)
    np.testing.assert_allclose(g[:3, 2], [0.0, 0.0, -1.0], atol=1e-9)
    # the top face is 0.3 x 0.06: the fingers close across the 6 cm side (local z)
    assert abs(float(g[:3, 1] @ pose[:3, 2])) == pytest.approx(1.0)
    np.testing.assert_allclose(g[2, 3], 0.02 + 0.02 - min(GRASP_DEPTH, 0.02), atol=1e-9)


def test_a_box_too_wide_for_the_fingers_is_refused_with_the_widths() -> None:
    with pytest.raises(GraspError, match=r"15\.0 cm across at its narrowest.*open 10\.0 cm"):
        top_grasp((1.2, 0.15, 0.02), np.eye(4), max_opening=0.1)
