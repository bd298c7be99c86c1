"""Grasp frames from an object's box, PlanBaseForGrasp, MoveToPose grasp="top" and
ObjectUpright."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest
from bhelpers import place_robot, reasons, run_xml

from bt_manip.geometry import pose_matrix, quat_from_euler
from bt_manip.grasps import GRASP_DEPTH, GraspError, top_grasp
from bt_manip.perception import perceived_pose, true_pose
from bt_manip.run.faults import FaultInjector, FaultSpec
from bt_manip.sim.world import World

HERE = Path(__file__).resolve().parent
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


# -- PlanBaseForGrasp ---------------------------------------------------------------------------


@pytest.fixture
def grasp_room() -> Iterator[World]:
    with World(HERE / "grasp_room.yaml", seed=0) as world:
        yield world


def _clearance(world: World, body: int, others: list[int], limit: float = 0.5) -> float:
    best = limit
    for other in others:
        for p in pb.getClosestPoints(body, other, limit, physicsClientId=world.client):
            best = min(best, p[8])
    return best


def test_plan_base_for_grasp_finds_a_collision_free_pose_the_arm_reaches_from(
    grasp_room: World,
) -> None:
    world = grasp_room
    report, tree = run_xml(
        world,
        '<PlanBaseForGrasp object="panel" base_pose="{base}" staging_pose="{staging}"'
        ' grasp_pose="{grasp}"/>',
    )
    assert report.status == "SUCCESS", report.reason
    bb = tree.blackboard
    x, y, yaw = (float(v) for v in bb.get("base").split(";"))
    sx, sy, syaw = (float(v) for v in bb.get("staging").split(";"))
    assert syaw == pytest.approx(yaw)
    assert math.hypot(sx - x, sy - y) == pytest.approx(0.7, abs=1e-3)  # lined up behind
    grasp = [float(v) for v in bb.get("grasp").split(";")]
    assert grasp[:3] == pytest.approx([0.5, 0.0, 0.12], abs=1e-6)  # middle of the top edge
    # the robot placed there (test setup) touches nothing and keeps its distance
    place_robot(world, "husky", x, y, yaw)
    robot = world.robots["husky"]
    static = [world.body_id(n) for n in ("wall_south", "wall_north", "wall_west", "wall_east")]
    assert _clearance(world, robot.body, [*static, world.movable["panel"]]) > 0.05
    # and from there the arm takes the grasp: home, then down a straight line onto the edge
    report, _ = run_xml(
        world,
        '<Sequence><OpenGripper/><MoveJoints state="home"/>'
        '<MoveToPose object="panel" grasp="top" approach="0.12" tolerance="0.002"/></Sequence>',
    )
    assert report.status == "SUCCESS", reasons(report)
    tip = robot.link_transform(robot.description.grasp_frame)
    assert np.linalg.norm(tip[:3, 3] - np.array(grasp[:3])) < 0.005
    assert tip[2, 2] < -0.999  # pointing straight down


WALLED = """
furniture:
  - {name: pen_n, shape: box, size: [2.0, 0.1, 1.0], pose: [0.5, 0.45, 0.0]}
  - {name: pen_s, shape: box, size: [2.0, 0.1, 1.0], pose: [0.5, -0.45, 0.0]}
  - {name: pen_e, shape: box, size: [0.1, 0.8, 1.0], pose: [1.45, 0.0, 0.0]}
  - {name: pen_w, shape: box, size: [0.1, 0.8, 1.0], pose: [-0.45, 0.0, 0.0]}
"""


def test_plan_base_for_grasp_fails_with_the_reason_when_the_object_is_walled_in(
    tmp_path: Path,
) -> None:
    text = (HERE / "grasp_room.yaml").read_text()
    text = text.replace("rpy: [0.0, 0.0, 0.5236]", "rpy: [0.0, 0.0, 0.0]")
    path = tmp_path / "walled.yaml"
    path.write_text(text.replace("objects:", WALLED.strip() + "\nobjects:"))
    with World(path, seed=0) as world:
        report, tree = run_xml(world, '<PlanBaseForGrasp object="panel" base_pose="{base}"/>')
        assert report.status == "FAILURE"
        why = reasons(report)["PlanBaseForGrasp"]
        assert why.startswith("no base pose from which the arm reaches panel: 480 poses sampled")
        assert "too close to an obstacle" in why
        assert not tree.blackboard.has_value("base")


def test_plan_base_for_grasp_refuses_an_object_the_fingers_cannot_span(
    grasp_room: World,
) -> None:
    world = grasp_room
    body = world.movable["panel"]
    # test setup: the panel laid flat on the floor
    pb.resetBasePositionAndOrientation(
        body, [0.5, 0.0, 0.01], quat_from_euler((math.pi / 2, 0.0, 0.5236)),
        physicsClientId=world.client,
    )
    report, _ = run_xml(world, '<PlanBaseForGrasp object="panel" base_pose="{base}"/>')
    assert report.status == "FAILURE"
    assert reasons(report)["PlanBaseForGrasp"] == (
        "cannot grasp 'panel': its top face is 15.0 cm across at its narrowest, and the fingers "
        "open 10.0 cm"
    )


def test_plans_read_the_perceived_pose_and_checks_the_true_one(grasp_room: World) -> None:
    world = grasp_room
    faults = FaultInjector([FaultSpec("pose_noise", 0.0, sigma_m=0.02, sigma_deg=3.0)], seed=5)
    offset = faults.pose_offset("panel")
    assert offset is not None
    seen = perceived_pose(world, faults, "panel")
    truth = true_pose(world, world.movable["panel"])
    np.testing.assert_allclose(seen[:2, 3] - truth[:2, 3], [offset.dx, offset.dy], atol=1e-12)
    assert seen[2, 3] == truth[2, 3]
    turn = math.atan2(seen[1, 0], seen[0, 0]) - math.atan2(truth[1, 0], truth[0, 0])
    assert math.remainder(turn - offset.dyaw, math.tau) == pytest.approx(0.0, abs=1e-9)
    assert perceived_pose(world, None, "panel").tolist() == truth.tolist()


# -- ObjectUpright ------------------------------------------------------------------------------


def test_object_upright_tells_a_standing_panel_from_a_fallen_one(grasp_room: World) -> None:
    world = grasp_room
    report, _ = run_xml(world, '<ObjectUpright object="panel" max_tilt="30"/>')
    assert report.status == "SUCCESS"
    pb.resetBasePositionAndOrientation(  # test setup: the panel lies on its face
        world.movable["panel"], [0.5, 0.0, 0.01], quat_from_euler((math.pi / 2, 0.0, 0.5236)),
        physicsClientId=world.client,
    )
    world.step(24)
    report, _ = run_xml(world, '<ObjectUpright object="panel" max_tilt="30"/>')
    assert report.status == "FAILURE"
    assert reasons(report)["ObjectUpright"] == (
        "'panel' fell over: it is tilted 90 deg from upright (more than 30 deg), and the gripper "
        "cannot take it from above"
    )


def _tip(world: World, roll: float, spin: tuple[float, float, float]) -> None:
    """Test setup: the panel stands on its long bottom edge at ``roll`` from upright, turning
    at ``spin`` (rad/s, world)."""
    c, s = math.cos(0.5236), math.sin(0.5236)
    # the bottom edge stays on the floor: the centre is half the height up the tilted panel
    h = 0.075
    pos = [0.5 - s * h * math.sin(roll), c * h * math.sin(roll), h * math.cos(roll) + 0.01]
    pb.resetBasePositionAndOrientation(
        world.movable["panel"], pos, quat_from_euler((roll, 0.0, 0.5236)),
        physicsClientId=world.client,
    )
    pb.resetBaseVelocity(world.movable["panel"], [0, 0, 0], spin, physicsClientId=world.client)


def test_object_upright_judges_a_falling_panel_once_it_is_at_rest(grasp_room: World) -> None:
    world = grasp_room
    c, s = math.cos(0.5236), math.sin(0.5236)
    _tip(world, math.radians(40), (3.0 * c, 3.0 * s, 0.0))  # falling onto its face
    report, _ = run_xml(world, '<ObjectUpright object="panel" max_tilt="30"/>')
    assert report.status == "SUCCESS"  # still falling: not judged yet
    # ticked until it fails: that is once the panel lies still, flat
    report, _ = run_xml(
        world, '<KeepRunningUntilFailure><ObjectUpright object="panel"/></KeepRunningUntilFailure>'
    )
    assert report.status == "FAILURE"
    assert "'panel' fell over: it is tilted 90 deg" in reasons(report)["ObjectUpright"]
    linear, angular = pb.getBaseVelocity(world.movable["panel"], physicsClientId=world.client)
    assert np.linalg.norm(linear) <= 0.05 and np.linalg.norm(angular) <= 0.3


def test_object_upright_waits_for_rest_no_longer_than_settle(grasp_room: World) -> None:
    world = grasp_room
    _tip(world, math.pi / 2, (0.0, 0.0, 30.0))  # lying flat, spinning fast on the floor
    report, _ = run_xml(
        world,
        '<KeepRunningUntilFailure><ObjectUpright object="panel" settle="0.1"/>'
        "</KeepRunningUntilFailure>",
    )
    assert report.status == "FAILURE"
    assert "'panel' fell over" in reasons(report)["ObjectUpright"]
    _, angular = pb.getBaseVelocity(world.movable["panel"], physicsClientId=world.client)
    assert np.linalg.norm(angular) > 0.3  # judged while it still turns
