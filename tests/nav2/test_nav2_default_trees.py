"""Every default tree of Nav2's nav2_bt_navigator, on Nav2's main branch and the Kilted,
Jazzy and Humble releases (Humble's are BehaviorTree.CPP v3 files, read through the v3 -> v4
conversion), end to end on the Husky in the house: each reaches the goal.

The trees are read from ``../shared/samples/nav2/<release>/`` (relative to the project's root);
the tests skip when they are not there.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import bt_manip.nav2  # noqa: F401  (registers the Nav2 nodes)
from bt_manip.bt import load_tree
from bt_manip.bt.status import NodeStatus
from bt_manip.run.context import RunContext
from bt_manip.sim.world import World

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = ROOT.parent / "shared" / "samples" / "nav2"
RELEASES = ("main", "kilted", "jazzy", "humble")
HOUSE = ROOT / "worlds" / "tb3_house.yaml"
SQUARE = ROOT / "worlds" / "calibration_square.yaml"
GOAL = (2.616, -0.715, 0.848)
GOAL_TEXT = "2.616;-0.715;0.848"
GOALS_TEXT = "-0.5;-1.5;0|2.616;-0.715;0.848"
WITH_GOALS = ("navigate_through_poses", "navigate_on_route_graph", "navigate_w_routing")
TICK_HZ = 20.0
FOLLOW_RADIUS = 1.0
"""follow_point.xml must keep the robot's turning point (where Nav2's base frame of a
skid-steer base is; the Husky's frame is 0.13 m behind it) this close to the goal..."""
FOLLOW_HOLD = 5.0
"""...for this long (s of sim time)."""


def _trees() -> list[object]:
    found = [
        pytest.param(release, f.name, id=f"{release}/{f.stem}", marks=pytest.mark.slow)
        for release in RELEASES
        for f in sorted((SAMPLES / release).glob("*.xml"))
        if f.name != "nav2_tree_nodes.xml"
    ]
    return found or [pytest.param("", "", id="absent", marks=pytest.mark.skip(
        reason=f"Nav2's default trees are not in {SAMPLES} (../shared/samples/nav2)"))]


def _tick(world: World, tree: object) -> NodeStatus:
    status = tree.tick()  # type: ignore[attr-defined]
    world.step(max(1, round(world.rate_hz / TICK_HZ)))
    return status  # type: ignore[no-any-return]


def _load(world: World, path: Path, blackboard: dict[str, object]) -> object:
    return load_tree(str(path), context=RunContext.for_world(world), blackboard=blackboard)


@pytest.mark.parametrize(("release", "name"), _trees())
def test_default_tree_reaches_its_goal(release: str, name: str) -> None:
    path = SAMPLES / release / name
    if name == "odometry_calibration.xml":
        with World(SQUARE, seed=3) as world:
            tree = _load(world, path, {})
            status = NodeStatus.RUNNING
            for _ in range(int(200 * TICK_HZ)):
                status = _tick(world, tree)
                if status is not NodeStatus.RUNNING:
                    break
            assert status is NodeStatus.SUCCESS
        return
    blackboard: dict[str, object] = {"goal": GOAL_TEXT}
    if name.startswith(WITH_GOALS):
        blackboard["goals"] = GOALS_TEXT
    with World(HOUSE, seed=3) as world:
        tree = _load(world, path, blackboard)
        robot = world.robots["husky"]
        if name == "follow_point.xml":
            near_since: float | None = None
            pivot = float(robot.description.base.pivot_offset)
            for _ in range(int(90 * TICK_HZ)):
                assert _tick(world, tree) is NodeStatus.RUNNING  # it never ends by design
                x, y, yaw = robot.base_pose2d()
                x, y = x + pivot * math.cos(yaw), y + pivot * math.sin(yaw)
                near = math.hypot(x - GOAL[0], y - GOAL[1]) <= FOLLOW_RADIUS
                now = world.time
                near_since = (near_since if near_since is not None else now) if near else None
                if near_since is not None and now - near_since >= FOLLOW_HOLD:
                    return
            pytest.fail(f"the robot did not stay within {FOLLOW_RADIUS} m of the goal for "
                        f"{FOLLOW_HOLD} s")
        status = NodeStatus.RUNNING
        for _ in range(int(150 * TICK_HZ)):
            status = _tick(world, tree)
            if status is not NodeStatus.RUNNING:
                break
        assert status is NodeStatus.SUCCESS
        x, y, yaw = robot.base_pose2d()
        assert math.hypot(x - GOAL[0], y - GOAL[1]) <= 0.25
        assert abs(math.remainder(yaw - GOAL[2], math.tau)) <= 0.25
