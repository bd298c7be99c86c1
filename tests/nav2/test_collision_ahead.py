"""FollowPath stops for an object that appears on the path in front of the robot, and an
injected ``block`` crate falls there, in front of the robot, when it comes near."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest

import bt_manip.nav2  # noqa: F401  (registers the Nav2 nodes)
from bt_manip.bt import load_tree_string
from bt_manip.bt.status import NodeStatus
from bt_manip.nav2.collision_ahead import stretch_ahead
from bt_manip.run.context import RunContext
from bt_manip.run.faults import BLOCK_NEAR, FaultInjector, FaultSpec, PendingBlock, plan_block
from bt_manip.sim.world import World

ROOM = Path(__file__).resolve().parent / "room.yaml"
FOLLOW = ('<Sequence><ComputePathToPose goal="{goal}" path="{path}"/>'
          '<FollowPath path="{path}" error_code_id="{code}" error_msg="{msg}"/></Sequence>')


@pytest.fixture
def room() -> Iterator[World]:
    with World(ROOM, seed=0) as world:
        yield world


def follow_tree(world: World, faults: FaultInjector | None = None) -> tuple[object, RunContext]:
    context = RunContext.for_world(world, faults=faults)
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="Main">{FOLLOW}</BehaviorTree></root>'
    return load_tree_string(xml, context=context, blackboard={"goal": "1.8;0.5;0.0"}), context


def contacts_with(world: World, body: int) -> int:
    robot = world.robots["husky"].body
    return len(pb.getContactPoints(bodyA=robot, bodyB=body, physicsClientId=world.client))


def test_stretch_ahead_starts_at_the_nearest_point_and_ends_at_the_lookahead() -> None:
    points = np.column_stack([np.arange(0.0, 5.0, 0.1), np.zeros(50)])
    ahead, s = stretch_ahead(points, (1.02, 0.3), lookahead=1.0)
    assert ahead[0] == pytest.approx((1.0, 0.0))
    assert s[-1] <= 1.0 + 1e-9
    assert ahead[-1][0] == pytest.approx(2.0)


def test_follow_path_stops_before_an_object_put_on_the_path_ahead(room: World) -> None:
    tree, _ = follow_tree(room)
    crate = room.movable["crate"]
    status = tree.tick()
    path = tree.blackboard.get("path")
    points = path.poses[:, :2]
    for _ in range(400):
        assert status is NodeStatus.RUNNING
        x, y, _ = room.robots["husky"].base_pose2d()
        ahead, s = stretch_ahead(points, (x, y), lookahead=3.0)
        if s[-1] > 2.0 and x > -1.0:
            # 0.9 m ahead of the robot, on its path
            spot = ahead[int(np.searchsorted(s, 0.9))]
            pb.resetBasePositionAndOrientation(crate, [spot[0], spot[1], 0.15], [0, 0, 0, 1],
                                               physicsClientId=room.client)
            break
        room.step(12)
        status = tree.tick()
    for _ in range(20):  # at most a second later (the check runs at 5 Hz)
        room.step(12)
        status = tree.tick()
        if status is not NodeStatus.RUNNING:
            break
    assert status is NodeStatus.FAILURE
    assert tree.blackboard.get("code") == 106  # NO_VALID_CONTROL
    assert tree.blackboard.get("msg").startswith("collision ahead: 'crate' lies on the path")
    room.step(120)
    assert contacts_with(room, crate) == 0  # it stopped short of the crate


def test_plan_block_draws_the_middle_of_the_route_away_from_its_ends() -> None:
    route = np.column_stack([np.linspace(0.0, 6.0, 61), np.zeros(61)])
    injector = FaultInjector([FaultSpec("block", 1.0)], seed=4)
    block = plan_block(injector, route, "goal")
    assert block == PendingBlock(3.0, 0.0, "goal")
    short = np.column_stack([np.linspace(0.0, 2.5, 26), np.zeros(26)])
    assert plan_block(injector, short, "goal") is None  # no point 1.5 m from both ends
    assert [e.kind for e in injector.events] == ["block"]


def test_a_pending_crate_is_due_only_near_its_place() -> None:
    injector = FaultInjector([FaultSpec("block", 1.0)], seed=0)
    injector.defer_block("husky", PendingBlock(3.0, 0.0, "goal"))
    assert injector.due_block("husky", 3.0 - BLOCK_NEAR - 0.05, 0.0) is None
    assert injector.due_block("other", 3.0, 0.0) is None
    assert injector.due_block("husky", 3.0 - BLOCK_NEAR + 0.05, 0.0) == PendingBlock(
        3.0, 0.0, "goal")
    assert injector.due_block("husky", 3.0, 0.0) is None  # it fell: no longer pending


def test_an_injected_crate_falls_in_front_of_the_robot_and_follow_path_stops_for_it(
        room: World) -> None:
    room.remove("crate")
    faults = FaultInjector([FaultSpec("block", 1.0)], seed=0, clock=room.clock)
    tree, _ = follow_tree(room, faults)
    status = tree.tick()
    pending = faults.pending_blocks["husky"]
    assert "dropped_crate_0" not in room.movable  # not yet: the robot is far from its place
    for _ in range(600):
        if status is not NodeStatus.RUNNING:
            break
        room.step(12)
        status = tree.tick()
    assert status is NodeStatus.FAILURE
    assert tree.blackboard.get("code") == 106
    assert "'dropped_crate_0' lies on the path" in tree.blackboard.get("msg")
    x, y, yaw = room.robots["husky"].base_pose2d()
    pivot = room.robots["husky"].description.base.pivot_offset
    px, py = x + pivot * math.cos(yaw), y + pivot * math.sin(yaw)
    gap = math.hypot(pending.x - px, pending.y - py)
    assert BLOCK_NEAR - 0.2 <= gap <= BLOCK_NEAR + 1e-6
    room.step(120)
    crate = room.movable["dropped_crate_0"]
    cx, cy, _ = pb.getBasePositionAndOrientation(crate, physicsClientId=room.client)[0]
    assert math.hypot(cx - pending.x, cy - pending.y) <= 0.05  # it fell where it was drawn
    assert contacts_with(room, crate) == 0
