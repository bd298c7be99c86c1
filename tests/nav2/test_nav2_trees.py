"""Nav2's default tree, navigate_to_pose_w_replanning_and_recovery.xml, end to end on the Husky:
to the house's goal, and through its recovery branch when the goal is walled in by crates."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import bt_manip.nav2  # noqa: F401  (registers the Nav2 nodes)
from bt_manip.bt import Tree, load_tree
from bt_manip.bt.status import NodeStatus
from bt_manip.run.context import RunContext
from bt_manip.sim.world import World
from bt_manip.sim.world_spec import COLOURS, BodySpec, Part, Pose3D, Range2D

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = ROOT.parent / "shared" / "samples" / "nav2"
DEFAULT_TREE = SAMPLES / "navigate_to_pose_w_replanning_and_recovery.xml"
RECOVERIES = ("ClearingActions", "Spin", "Wait", "BackUp")

pytestmark = pytest.mark.skipif(
    not DEFAULT_TREE.is_file(), reason="Nav2's sample trees are not in ../shared/samples/nav2"
)


def load(world: World, goal: str) -> Tree:
    return load_tree(
        str(DEFAULT_TREE), context=RunContext.for_world(world),
        blackboard={"goal": goal},
    )


def run(world: World, tree: Tree, max_ticks: int = 2400,
        on_tick: Callable[[list[str]], None] | None = None) -> tuple[NodeStatus, list[str]]:
    """Tick at 20 Hz (12 physics steps a tick) until the root finishes; the recoveries of the
    RoundRobin in the order they started."""
    started: list[str] = []
    status = NodeStatus.RUNNING
    for _ in range(max_ticks):
        status = tree.tick()
        names = [n.name for n in tree.visited_nodes()]
        for name in names:
            if name in RECOVERIES and (not started or started[-1] != name):
                started.append(name)
        if on_tick is not None:
            on_tick(started)
        if status is not NodeStatus.RUNNING:
            break
        world.step(12)
    return status, started


def test_default_tree_reaches_the_house_goal() -> None:
    with World(ROOT / "worlds" / "tb3_house.yaml", seed=3) as world:
        status, recoveries = run(world, load(world, "2.616;-0.715;0.848"))
        assert status is NodeStatus.SUCCESS
        assert recoveries == []
        x, y, yaw = world.robots["husky"].base_pose2d()
        assert math.hypot(x - 2.616, y + 0.715) <= 0.25
        assert abs(math.remainder(yaw - 0.848, math.tau)) <= 0.25


def crate_ring(world: World, centre: tuple[float, float], radius: float, n: int) -> list[str]:
    """``n`` crates in a ring round ``centre``: too close together for the Husky to pass."""
    names = []
    for k in range(n):
        a = 2 * math.pi * k / n
        name = f"ring_{k}"
        world.spawn(BodySpec(
            name=name, movable=True,
            parts=[Part("box", (0.3, 0.3, 0.3), colour=COLOURS["brown"])],
            urdf=None,
            pose=Pose3D((centre[0] + radius * math.cos(a), centre[1] + radius * math.sin(a), 0.15)),
            planar=False, mass=8.0, friction=0.9, colour=COLOURS["brown"],
            randomize=Range2D(), line=0,
        ))
        names.append(name)
    world.step(48)
    return names


def test_recoveries_take_turns_until_the_retries_are_spent() -> None:
    with World(Path(__file__).resolve().parent / "room.yaml", seed=0) as world:
        crate_ring(world, (1.6, 0.5), 0.85, 12)
        tree = load(world, "1.6;0.5;0.0")
        status, recoveries = run(world, tree)
        assert status is NodeStatus.FAILURE
        # six retries of the navigation, one recovery before each, in RoundRobin order
        assert recoveries == ["ClearingActions", "Spin", "Wait", "BackUp", "ClearingActions",
                              "Spin"]
        assert tree.blackboard.get("compute_path_error_code") == 208  # NO_VALID_PATH


def test_the_goal_is_reached_once_a_recovery_gave_the_world_time_to_change() -> None:
    with World(Path(__file__).resolve().parent / "room.yaml", seed=0) as world:
        ring = crate_ring(world, (1.6, 0.5), 0.85, 12)
        tree = load(world, "1.6;0.5;0.0")

        def open_the_ring(started: list[str]) -> None:
            if started[-1:] == ["Wait"] and "ring_6" in world.movable:
                for name in ring[5:8]:  # the crates on the robot's side
                    world.remove(name)

        status, recoveries = run(world, tree, on_tick=open_the_ring)
        assert status is NodeStatus.SUCCESS
        assert recoveries == ["ClearingActions", "Spin", "Wait"]
        x, y, _ = world.robots["husky"].base_pose2d()
        assert math.hypot(x - 1.6, y - 0.5) <= 0.25


def test_validate_and_the_groot_model_know_nav2s_nodes(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    from bt_manip import cli

    assert cli.main(["validate", str(DEFAULT_TREE)]) == 0
    assert ": OK" in capsys.readouterr().out
    assert cli.main(["nodes", "--groot"]) == 0
    model = capsys.readouterr().out
    for node_id in ("PipelineSequence", "RecoveryNode", "RoundRobin", "RateController",
                    "ComputePathToPose", "FollowPath", "ClearEntireCostmap", "Spin", "Wait",
                    "BackUp", "GoalUpdated", "WouldAPlannerRecoveryHelp",
                    "WouldAControllerRecoveryHelp"):
        assert f'ID="{node_id}"' in model
    path = tmp_path / "nav2_model.xml"
    path.write_text(model)
    assert cli.main(["validate", str(DEFAULT_TREE), "--models", str(path)]) == 0


REPLAN_IF_INVALID = """
<root BTCPP_format="4">
  <BehaviorTree ID="ReplanWhenBlocked">
    <PipelineSequence>
      <PlannerSelector selected_planner="{planner}" default_planner="GridBased"/>
      <RateController hz="2.0">
        <Fallback>
          <ReactiveSequence>
            <Inverter><GlobalUpdatedGoal/></Inverter>
            <IsPathValid path="{path}"/>
          </ReactiveSequence>
          <ComputePathToPose goal="{goal}" path="{path}" planner_id="{planner}"/>
        </Fallback>
      </RateController>
      <FollowPath path="{path}" error_code_id="{follow_code}"/>
    </PipelineSequence>
  </BehaviorTree>
</root>
"""


def test_a_path_made_invalid_is_planned_again_and_followed_round_the_obstacle() -> None:
    import pybullet as pb

    with World(Path(__file__).resolve().parent / "room.yaml", seed=0) as world:
        tree = load_tree(
            "replan.xml", text=REPLAN_IF_INVALID,
            context=RunContext.for_world(world), blackboard={"goal": "east"},
        )
        assert tree.tick() is NodeStatus.RUNNING
        first = tree.blackboard.get("path")
        ahead = first.poses[int(np.argmin(np.abs(first.poses[:, 0] - 0.0)))]
        crate = world.movable["crate"]
        pb.resetBasePositionAndOrientation(crate, [ahead[0], ahead[1], 0.15], [0, 0, 0, 1],
                                           physicsClientId=world.client)
        world.step(12)
        status, _ = run(world, tree)
        assert status is NodeStatus.SUCCESS
        assert tree.blackboard.get("path") is not first  # planned again
        moved, _ = pb.getBasePositionAndOrientation(crate, physicsClientId=world.client)
        assert math.hypot(moved[0] - ahead[0], moved[1] - ahead[1]) <= 0.02  # not pushed
        east = world.poses["east"]
        x, y, _ = world.robots["husky"].base_pose2d()
        assert math.hypot(x - east.x, y - east.y) <= 0.25


THROUGH_POSES = """
<root BTCPP_format="4">
  <BehaviorTree ID="ThroughPoses">
    <PipelineSequence>
      <RateController hz="1.0">
        <Sequence>
          <RemovePassedGoals input_goals="{goals}" output_goals="{goals}" radius="0.5"/>
          <ComputePathThroughPoses goals="{goals}" path="{path}" error_code_id="{code}"/>
        </Sequence>
      </RateController>
      <FollowPath path="{path}"/>
    </PipelineSequence>
  </BehaviorTree>
</root>
"""


def test_through_poses_passes_each_goal_and_ends_on_the_last() -> None:
    with World(Path(__file__).resolve().parent / "room.yaml", seed=0) as world:
        tree = load_tree(
            "through.xml", text=THROUGH_POSES,
            context=RunContext.for_world(world),
            blackboard={"goals": "-0.2;1.2;0|1.8;0.5;0"},
        )
        closest = [math.inf]

        def watch(_: list[str]) -> None:
            x, y, _ = world.robots["husky"].base_pose2d()
            closest[0] = min(closest[0], math.hypot(x + 0.2, y - 1.2))

        status, _ = run(world, tree, on_tick=watch)
        assert status is NodeStatus.SUCCESS
        assert closest[0] <= 0.5  # it went by the first goal
        x, y, _ = world.robots["husky"].base_pose2d()
        assert math.hypot(x - 1.8, y - 0.5) <= 0.25
        assert tree.blackboard.get("goals") == [(1.8, 0.5, 0.0)]  # the first one was passed
        assert tree.blackboard.get("code") == 0


def test_through_poses_without_goals_gives_no_viapoints() -> None:
    with World(Path(__file__).resolve().parent / "room.yaml", seed=0) as world:
        tree = load_tree(
            "through.xml", text=THROUGH_POSES,
            context=RunContext.for_world(world), blackboard={"goals": ""},
        )
        status, _ = run(world, tree)
        assert status is NodeStatus.FAILURE
        assert tree.blackboard.get("code") == 309  # NO_VIAPOINTS_GIVEN


def test_a_crate_falling_in_front_of_the_robot_takes_it_through_the_recovery_branch() -> None:
    from bt_manip.bench.episodes import count_leaf_failures
    from bt_manip.run.faults import FaultInjector, FaultSpec

    with World(ROOT / "worlds" / "tb3_house.yaml", seed=0) as world:
        faults = FaultInjector([FaultSpec("block", 1.0)], seed=0, clock=world.clock)
        tree = load_tree(str(DEFAULT_TREE), context=RunContext.for_world(world, faults=faults),
                         blackboard={"goal": "2.616;-0.715;0.848"})
        failures = count_leaf_failures(tree)
        status, recoveries = run(world, tree)
        assert status is NodeStatus.SUCCESS
        # FollowPath stopped for the crate, its own recovery (clearing the local costmap) did
        # not help, so the navigation failed once and the recovery branch's first turn ran
        assert failures["NavigateRecovery/NavigateWithReplanning/FollowPath/FollowPath"] == 2
        assert recoveries == ["ClearingActions"]
        assert [e.kind for e in faults.events] == ["block"]
        x, y, yaw = world.robots["husky"].base_pose2d()
        assert math.hypot(x - 2.616, y + 0.715) <= 0.25
        assert abs(math.remainder(yaw - 0.848, math.tau)) <= 0.25
        # the robot went round the crate: it lies where it fell
        import pybullet as pb

        drop = faults.report()[0]
        assert drop["kind"] == "block"
        crate = world.movable["dropped_crate_0"]
        cx, cy, _ = pb.getBasePositionAndOrientation(crate, physicsClientId=world.client)[0]
        route = tree.blackboard.get("path").poses[:, :2]
        assert np.hypot(route[:, 0] - cx, route[:, 1] - cy).min() >= 0.3


ROUTING_TREE = SAMPLES / "main" / "navigate_w_routing_global_planning_and_control_w_recovery.xml"


@pytest.mark.skipif(not ROUTING_TREE.is_file(), reason="Nav2's main-branch trees are missing")
def test_crates_on_the_route_are_routed_round_or_end_the_tree_within_its_retries() -> None:
    """The routing tree recomputes its route when ValidatePath finds the route's path blocked;
    the route server leaves out the edges blocked on the costmap (Nav2's CostmapScorer), so the
    new route goes another way, and when no way is left ComputeRoute's 405 ends the tree."""
    from bt_manip.run.faults import FaultInjector, FaultSpec

    with World(ROOT / "worlds" / "tb3_house.yaml", seed=0) as world:
        faults = FaultInjector([FaultSpec("block", 1.0)], seed=0, clock=world.clock)
        tree = load_tree(str(ROUTING_TREE), context=RunContext.for_world(world, faults=faults),
                         blackboard={"goal": "2.616;-0.715;0.848",
                                     "goals": "-0.5;-1.5;0|2.616;-0.715;0.848"})
        routes: list[list[int]] = []

        def watch(_: list[str]) -> None:
            route = tree.blackboard.get("route") if tree.blackboard.exists("route") else None
            if route is not None and (not routes or routes[-1] != [n.id for n in route.nodes]):
                routes.append([n.id for n in route.nodes])

        status, _ = run(world, tree, on_tick=watch)
        assert status is not NodeStatus.RUNNING  # it did not loop to the tick budget
        assert faults.events and faults.events[0].kind == "block"
        assert len(routes) >= 2  # the crate's edge was left out: the route went another way
        if status is NodeStatus.FAILURE:
            assert tree.blackboard.get("compute_route_error_code") == 405
