"""bt-manip's own Nav2-shaped trees (trees/nav2/) end to end on the Husky in the house, with
the goal given as ``--bb "goal=2.616;-0.715;0.848"`` gives it."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import bt_manip.nav2  # noqa: F401  (registers the Nav2 nodes)
from bt_manip import cli
from bt_manip.bt import Tree, load_tree
from bt_manip.cli.args import bb_pair
from bt_manip.run.context import RunContext
from bt_manip.run.report import RunReport
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.world import World

ROOT = Path(__file__).resolve().parents[2]
HOUSE = ROOT / "worlds" / "tb3_house.yaml"
TREES = ROOT / "trees" / "nav2"
GOAL = (2.616, -0.715, 0.848)
GOAL_TEXT = "2.616;-0.715;0.848"
REPLANNING_TREES = ("replan_on_distance", "replan_on_time", "replan_if_path_invalid",
                    "replan_on_goal_update")


def bb(**pairs: str) -> dict[str, Any]:
    """Blackboard entries as ``--bb key=value`` reads them."""
    return dict(bb_pair(f"{k}={v}") for k, v in pairs.items())


def load(world: World, name: str, entries: dict[str, Any]) -> Tree:
    return load_tree(str(TREES / f"{name}.xml"), context=RunContext.for_world(world),
                     blackboard=entries)


def run(world: World, name: str, entries: dict[str, Any]) -> tuple[RunReport, Tree]:
    tree = load(world, name, entries)
    return Runner(tree, world, RunOptions(max_sim_time=120.0)).run(), tree


def run_watching(world: World, name: str, entries: dict[str, Any],
                 on_tick: Callable[[Tree], None]) -> tuple[str, Tree]:
    """Tick at 20 Hz (12 physics steps a tick) until the root finishes or 120 s of sim time
    passed, calling ``on_tick`` between ticks; the root's last status."""
    tree = load(world, name, entries)
    status = tree.tick()
    while status.value == "RUNNING" and world.clock.now() < 120.0:
        on_tick(tree)
        world.step(12)
        status = tree.tick()
    return status.value, tree


def world_of(tree: Tree) -> World:
    world = tree.context.world
    assert isinstance(world, World)
    return world


def distance_to(world: World, x: float, y: float) -> float:
    px, py, _ = world.robots["husky"].base_pose2d()
    return math.hypot(px - x, py - y)


@pytest.mark.parametrize("name", REPLANNING_TREES)
def test_each_tree_reaches_the_house_goal(name: str) -> None:
    with World(HOUSE, seed=4) as world:
        report, _ = run(world, name, bb(goal=GOAL_TEXT))
        assert report.status == "SUCCESS", report.reason
        x, y, yaw = world.robots["husky"].base_pose2d()
        assert math.hypot(x - GOAL[0], y - GOAL[1]) <= 0.25
        assert abs(math.remainder(yaw - GOAL[2], math.tau)) <= 0.25


def test_the_trees_validate_and_their_headers_name_the_nav2_pattern(
        capsys: pytest.CaptureFixture[str]) -> None:
    for path in sorted(TREES.glob("*.xml")):
        assert cli.main(["validate", str(path)]) == 0, capsys.readouterr()
        assert "Pattern: Nav2's" in path.read_text()


def test_a_goal_sent_on_the_way_is_taken_by_the_goal_update_tree() -> None:
    new_goal = (3.0, -3.0, 0.0)  # the living room's south side
    sent: list[float] = []

    def send_when_half_way(tree: Tree) -> None:
        if not sent and distance_to(world_of(tree), GOAL[0], GOAL[1]) < 3.0:
            tree.blackboard.set("goal_update", ";".join(str(v) for v in new_goal))
            sent.append(world_of(tree).clock.now())

    with World(HOUSE, seed=4) as world:
        status, tree = run_watching(world, "replan_on_goal_update", bb(goal=GOAL_TEXT),
                                    send_when_half_way)
        assert sent, "the robot never came within 3 m of the first goal"
        assert status == "SUCCESS"
        assert distance_to(world, new_goal[0], new_goal[1]) <= 0.25
        assert tree.blackboard.get("current_goal") == "3.0;-3.0;0.0"
        assert tree.blackboard.get("path").goal == pytest.approx(new_goal)


def test_the_goal_update_tree_does_not_set_off_on_a_low_battery() -> None:
    with World(HOUSE, seed=4) as world:
        start = world.robots["husky"].base_pose2d()
        report, _ = run(world, "replan_on_goal_update",
                        bb(goal=GOAL_TEXT, battery_status="0.05"))
        assert report.status == "FAILURE"
        assert report.sim_time < 1.0
        assert "BatteryNotLow" in str(report.reason)
        # the cause names the reading the Inverter failed on, not just the Inverter
        assert "because IsBatteryLow" in str(report.reason)
        assert "battery at 0.050 <= " in str(report.reason)
        assert distance_to(world, start[0], start[1]) < 0.05


def test_the_through_poses_tree_passes_the_waypoint_and_ends_on_the_goal() -> None:
    waypoint = (-0.5, -1.5)
    closest = [math.inf]

    def watch(tree: Tree) -> None:
        closest[0] = min(closest[0], distance_to(world_of(tree), *waypoint))

    with World(HOUSE, seed=4) as world:
        status, tree = run_watching(world, "through_poses",
                                    bb(goals=f"{waypoint[0]};{waypoint[1]};0|{GOAL_TEXT}"), watch)
        assert status == "SUCCESS"
        assert closest[0] <= 0.7  # RemovePassedGoals' radius
        assert distance_to(world, GOAL[0], GOAL[1]) <= 0.25
        assert tree.blackboard.get("goals") == [GOAL]  # the waypoint was dropped once passed
