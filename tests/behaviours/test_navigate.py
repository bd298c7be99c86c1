"""Navigate and Reverse on the Husky in the house."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest
from bhelpers import place_robot, reasons, run_xml

from bt_manip.bt import load_tree_string
from bt_manip.navigation.navigator import NavigatorOptions
from bt_manip.run.context import RunContext
from bt_manip.run.faults import FaultInjector, FaultSpec
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.world import World

ROOT = Path(__file__).resolve().parents[2]
HOUSE = ROOT / "worlds" / "tb3_house.yaml"


def test_navigate_to_coordinates_and_to_a_named_pose() -> None:
    with World(HOUSE, seed=2) as world:
        x0, y0, _ = world.robots["husky"].base_pose2d()
        xml = (
            '<Sequence><MoveJoints state="tuck"/>'
            '<Navigate goal="-1.5;-2.5;1.57" path_length="{len}"/>'
            '<Navigate goal="start" xy_tolerance="0.03" yaw_tolerance="0.03"/></Sequence>'
        )
        report, tree = run_xml(world, xml, 120)
        assert report.status == "SUCCESS", report.reason
        x, y, yaw = world.robots["husky"].base_pose2d()
        start = world.poses["start"]
        assert math.hypot(x - start.x, y - start.y) <= 0.03
        assert abs(math.remainder(yaw - start.yaw, math.tau)) <= 0.03
        # the first leg: no shorter than the straight line from where the robot started
        assert tree.blackboard.as_dict()["len"] >= math.hypot(-1.5 - x0, -2.5 - y0) - 0.05
        # both legs drove with the run's one navigator; the second leg's tolerances were its
        # own and did not become the navigator's
        assert isinstance(tree.context, RunContext)
        nav = tree.context.robot_services("husky").navigator
        assert nav.options.follower == NavigatorOptions().follower
        assert nav.options.follower.xy_tolerance != 0.03
        report, _ = run_xml(world, '<Navigate goal="kitchen"/>')
        assert "goal 'kitchen' is neither a named pose" in reasons(report)["Navigate"]
        report, _ = run_xml(world, '<Navigate goal="2.6;4.6;0"/>')  # inside the counter
        assert reasons(report)["Navigate"].startswith("no path to 2.6;4.6;0:")


def test_a_crate_dropped_on_the_route_is_not_pushed_along() -> None:
    with World(HOUSE, seed=0) as world:
        faults = FaultInjector([FaultSpec("block", 1.0)], seed=0, clock=world.clock)
        xml = (
            '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>'
            '<MoveJoints state="tuck"/><Navigate goal="goal"/></Sequence>'
            "</BehaviorTree></root>"
        )
        context = RunContext.for_world(world, faults=faults)
        tree = load_tree_string(xml, context=context)
        landed: dict[str, np.ndarray] = {}

        def watch(_: Runner) -> None:
            for name, body in world.movable.items():
                pos = np.array(
                    pb.getBasePositionAndOrientation(body, physicsClientId=world.client)[0]
                )
                if name.startswith("dropped_crate") and world.time > 1.5:
                    landed.setdefault(name, pos)
                    assert np.linalg.norm(pos - landed[name]) < 0.05, f"{name} was pushed"

        report = Runner(tree, world, RunOptions(max_sim_time=90), on_tick=[watch]).run()
        assert [e.kind for e in faults.events] == ["block"]
        assert "dropped_crate_0" in landed
        # it went around the crate, or stopped at it and said so
        assert report.status == "SUCCESS" or "ran into 'dropped_crate_0'" in report.reason


def test_reverse_backs_straight_up_and_stops_at_a_wall() -> None:
    with World(HOUSE, seed=0) as world:
        place_robot(world, "husky", 0.0, -2.0, 0.0)
        report, _ = run_xml(world, '<Reverse distance="0.6"/>')
        assert report.status == "SUCCESS", report.reason
        x, y, yaw = world.robots["husky"].base_pose2d()
        assert x == pytest.approx(-0.6, abs=0.05) and abs(y + 2.0) < 0.05 and abs(yaw) < 0.05
        # 1.5 m from the west wall of the workshop: backing up 2 m must stop at it
        place_robot(world, "husky", -1.9, -2.0, 0.0)
        report, _ = run_xml(world, '<Reverse distance="2.0"/>')
        assert report.status == "FAILURE"
        assert "backing up, touched 'wall_x_m3'" in reasons(report)["Reverse"]


def test_the_bare_robot_drives_through_a_one_metre_doorway() -> None:
    with World(HOUSE, seed=0) as world:
        robot = world.robots["husky"]
        static = {
            i.body_id: i.name for i in world.infos.values() if i.kind in ("wall", "furniture")
        }
        touched: set[str] = set()

        def watch(_: Runner) -> None:
            for pt in pb.getContactPoints(bodyA=robot.body, physicsClientId=world.client):
                if pt[2] in static:
                    touched.add(static[pt[2]])

        xml = (
            '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>'
            '<MoveJoints state="tuck"/><Navigate goal="-4.6;2.6;3.14"/></Sequence>'
            "</BehaviorTree></root>"
        )
        tree = load_tree_string(xml, context=RunContext.for_world(world))
        report = Runner(tree, world, RunOptions(max_sim_time=60), on_tick=[watch]).run()
        assert report.status == "SUCCESS", report.reason
        x, y, _ = robot.base_pose2d()
        assert x < -3.3 and 1.6 < y < 4.9  # in bedroom 2, behind the 1.0 m doorway at x = -3
        assert touched == set()


def test_halted_actions_leave_the_robot_stopped_and_holding() -> None:
    with World(HOUSE, seed=0) as world:
        robot = world.robots["husky"]
        report, _ = run_xml(
            world,
            '<Sequence><MoveJoints state="tuck"/>'
            '<Timeout msec="1500"><Navigate goal="goal"/></Timeout></Sequence>',
        )
        assert report.status == "FAILURE"  # the Timeout halted the drive while it was running
        world.step(120)
        before = robot.base_pose2d()
        world.step(240)
        after = robot.base_pose2d()
        assert math.hypot(after[0] - before[0], after[1] - before[1]) < 0.005
        assert np.linalg.norm(robot.base_velocity()) < 0.01
        report, _ = run_xml(
            world,
            '<Timeout msec="300"><MoveJoints targets="90;-90;0;-90;0;0" speed="0.2"/></Timeout>',
        )
        assert report.status == "FAILURE"
        q = robot.arm_positions()
        world.step(240)
        assert np.allclose(robot.arm_positions(), q, atol=0.01)  # holding where it was halted
        assert not np.allclose(q, np.radians([90, -90, 0, -90, 0, 0]), atol=0.05)


def test_robot_behaviours_need_the_services_of_a_run() -> None:
    from bt_manip.bt import TreeContext

    with World(HOUSE, seed=0) as world:
        xml = (
            '<root BTCPP_format="4"><BehaviorTree ID="Main"><Navigate goal="goal"/>'
            "</BehaviorTree></root>"
        )
        tree = load_tree_string(xml, context=TreeContext(clock=world.clock, world=world))
        report = Runner(tree, world, RunOptions(max_sim_time=5)).run()
        assert report.status == "FAILURE"
        assert "RunContext.for_world(world)" in reasons(report)["Navigate"]
