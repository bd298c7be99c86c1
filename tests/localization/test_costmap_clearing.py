"""A stale mark and Nav2's clearing recovery, in a small room whose only way out is a doorway
onto open ground.

A crate stands in the doorway, absent from the map: it is not one of the world file's objects
(which the robot is told of) but put there as the run starts. Only two posts stand outside,
well off the line of sight through the doorway. The Husky, localising, plans straight
through it (it has not seen it), marks it once its laser comes within ``obstacle_max_range``,
and FollowPath stops for it (106). At that first failure the crate is taken away. Nothing
stands behind the doorway, so no beam ends beyond the crate's place and its marks are never
cleared by ray tracing: they are stale, and they close the only way out.

- With Nav2's recovery (ClearEntireCostmap on the local, then the global costmap) the marks
  go, the plan goes through the doorway and the robot reaches the goal.
- With a Wait instead, the stale global marks leave no path: the tree fails.
- Clearing only the local costmap leaves the global marks the planner reads: it fails too.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import Any

import pybullet as pb
import pytest

from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.localization.runtime import MARKS_DRAWN, static_frame
from bt_manip.navigation.layered import GLOBAL, RobotCostmaps
from bt_manip.navigation.navigator import Navigator
from bt_manip.run.runner import RunOptions
from bt_manip.run.status import RunStatus
from bt_manip.sim.world import World
from bt_manip.sim.world_spec import COLOURS, BodySpec, Part, Pose3D, Range2D
from bt_manip.viz.recorder import Recorder

WORLD = """name: doorway_room
walls:
  - {name: wall_south, from: [-2.0, -1.5], to: [2.0, -1.5], thickness: 0.15, height: 1.0}
  - {name: wall_north, from: [-2.0, 1.5], to: [2.0, 1.5], thickness: 0.15, height: 1.0}
  - {name: wall_west, from: [-2.0, -1.575], to: [-2.0, 1.575], thickness: 0.15, height: 1.0}
  - name: wall_east
    from: [2.0, -1.575]
    to: [2.0, 1.575]
    thickness: 0.15
    height: 1.0
    doors:
      - {at: 1.575, width: 1.2}
furniture:
  # a flat tile, below the laser and the robot's band: it only stretches the map to the goal
  - {name: tile, shape: box, size: [0.1, 0.1, 0.01], pose: [5.0, 0.0, 0.0], colour: grey}
  # two posts beside the goal, out of the line of sight through the doorway from the room:
  # the robot localises on them out there
  - {name: post_north, shape: cylinder, radius: 0.15, height: 1.0, pose: [3.5, 1.5, 0.0],
     colour: grey}
  - {name: post_south, shape: cylinder, radius: 0.15, height: 1.0, pose: [3.5, -1.5, 0.0],
     colour: grey}
robots:
  - name: husky
    description: husky_ur3
    pose: [-1.2, 0.0, 0.0]
    arm_state: tuck
"""
GOAL = (4.0, 0.0)
CRATE = (2.0, 0.0)
RECOVERIES = {
    "clear local then global": (
        '<Sequence>'
        '<ClearEntireCostmap service_name="local_costmap/clear_entirely_local_costmap"/>'
        '<ClearEntireCostmap service_name="global_costmap/clear_entirely_global_costmap"/>'
        '</Sequence>'),
    "wait": '<Wait wait_duration="1"/>',
    "clear local only": (
        '<ClearEntireCostmap service_name="local_costmap/clear_entirely_local_costmap"/>'),
}


def tree(recovery: str) -> str:
    return f"""<root BTCPP_format="4" main_tree_to_execute="ToGoal">
  <BehaviorTree ID="ToGoal">
    <RecoveryNode number_of_retries="3">
      <Sequence>
        <ComputePathToPose goal="{{goal}}" path="{{path}}"/>
        <FollowPath path="{{path}}"/>
      </Sequence>
      {RECOVERIES[recovery]}
    </RecoveryNode>
  </BehaviorTree>
</root>
"""


def marks_near(layer: Any, x: float, y: float, half: float = 0.3) -> int:
    return int((layer.marked & layer.square(x, y, half)).sum())


def run(tmp_path: Path, recovery: str) -> tuple[Any, dict[str, Any], tuple[float, float, float]]:
    world = tmp_path / "room.yaml"
    world.write_text(WORLD)
    xml = tmp_path / "tree.xml"
    xml.write_text(tree(recovery))
    spec = EpisodeSpec(tree=str(xml), world=str(world), seed=0, localize=True,
                       blackboard={"goal": f"{GOAL[0]};{GOAL[1]};0.0"},
                       options=RunOptions(max_sim_time=40.0))
    seen: dict[str, Any] = {}
    with Episode(spec) as episode:
        assert episode.world is not None and episode.localization is not None
        world_ = episode.world
        loc = episode.localization.localizers["husky"]
        assert loc.costmaps is not None
        world_.spawn(BodySpec(
            name="crate", movable=True, parts=[Part("box", (0.3, 0.3, 0.3))], urdf=None,
            pose=Pose3D((CRATE[0], CRATE[1], 0.15)), planar=False, mass=8.0, friction=0.9,
            colour=COLOURS["brown"], randomize=Range2D(), line=0))
        episode.localization()  # the first scan, as before the first tick
        seen["at_start"] = marks_near(loc.costmaps.layer(GLOBAL), *CRATE)
        follow = next(n for n in episode.tree.root.iterate() if type(n).__name__ == "FollowPath")
        fail = follow.fail

        def first_failure_takes_the_crate_away(code: int, reason: str) -> Any:
            if "reason" not in seen:
                x, y, _ = world_.robots["husky"].base_pose2d()
                seen["reason"] = reason
                seen["distance"] = math.hypot(CRATE[0] - x, CRATE[1] - y)
                seen["marked"] = marks_near(loc.costmaps.layer(GLOBAL), *CRATE)
                world_.remove("crate")
            return fail(code, reason)

        follow.fail = first_failure_takes_the_crate_away  # type: ignore[method-assign]
        recorder = Recorder(tmp_path / "replay.html", world_, episode.tree)
        report = episode.run(hooks=[recorder])
        seen["stale"] = marks_near(loc.costmaps.layer(GLOBAL), *CRATE)
        # the replay holds the global costmap's marks over time, as the overlay drew them
        seen["drawn"] = [
            len(obj["geometries"][0]["data"]["attributes"]["position"]["array"]) // 3
            for _, name, obj, _ in recorder.rec.overlay_events
            if name == "husky_costmap_marks" and obj is not None]
        pose = world_.robots["husky"].base_pose2d()
    return report, seen, pose


@pytest.mark.parametrize("recovery", list(RECOVERIES))
def test_a_stale_mark_blocks_the_doorway_until_the_costmaps_are_cleared(
        tmp_path: Path, recovery: str) -> None:
    report, seen, pose = run(tmp_path, recovery)
    # the crate is not in the map: it enters the obstacle layer once the laser sees it
    assert seen["at_start"] == 0
    assert "collision ahead" in seen["reason"]
    assert seen["marked"] > 0 and seen["distance"] < 2.5
    at_goal = math.hypot(pose[0] - GOAL[0], pose[1] - GOAL[1]) <= 0.3
    if recovery == "clear local then global":
        assert report.status is RunStatus.SUCCESS and at_goal
        assert report.costmap is not None
        assert report.costmap["global_clears"] >= 1 and report.costmap["local_clears"] >= 1
        assert seen["stale"] == 0
        # drawn as they grew, and again once cleared (the walls seen since, the crate gone)
        drawn = seen["drawn"]
        assert len(drawn) >= 3 and max(drawn) <= MARKS_DRAWN
        assert any(b < a for a, b in itertools.pairwise(drawn))
    else:
        assert report.status is RunStatus.FAILURE and not at_goal
        assert "no path" in report.reason or "footprint" in report.reason
        assert seen["stale"] > 0  # no beam saw through the doorway: the mark stayed
        assert pose[0] < CRATE[0] - 0.5


def test_the_navigator_knows_the_world_files_objects_and_only_sees_the_rest(
        tmp_path: Path) -> None:
    world_file = tmp_path / "room.yaml"
    world_file.write_text(WORLD.replace("robots:", (
        "objects:\n"
        "  - {name: panel, shape: box, size: [0.6, 0.1, 0.15], mass: 1.0, friction: 0.9,\n"
        "     colour: white, pose: [0.0, 1.0, 0.075]}\nrobots:")))
    with World(world_file, seed=0) as world:
        crate = world.spawn(BodySpec(
            name="crate", movable=True, parts=[Part("box", (0.3, 0.3, 0.3))], urdf=None,
            pose=Pose3D((1.0, -1.0, 0.15)), planar=False, mass=8.0, friction=0.9,
            colour=COLOURS["brown"], randomize=Range2D(), line=0))
        panel = world.body_id("panel")
        frame = static_frame(world)
        assert frame is not None
        robot = world.robots["husky"]
        nav = Navigator(robot, world.obstacle_body_ids(), world.movable,
                        layers=RobotCostmaps(frame), known=[panel])
        grid = nav.costmap.grid

        def occupied(x: float, y: float) -> bool:
            return bool(grid.occupied[grid.world_to_cell(x, y)])

        assert occupied(0.0, 1.0)  # told of: on the map from the start
        assert not occupied(1.0, -1.0)  # the crate: not seen yet, not drawn
        # the panel moves: the map keeps it where it was (no truth drawn)
        pb.resetBasePositionAndOrientation(panel, (0.0, -0.5, 0.075), (0, 0, 0, 1),
                                           physicsClientId=world.client)
        pb.resetBasePositionAndOrientation(crate, (-1.0, 1.0, 0.15), (0, 0, 0, 1),
                                           physicsClientId=world.client)
        assert not nav.refresh()
        grid = nav.costmap.grid
        assert occupied(0.0, 1.0) and not occupied(0.0, -0.5)
        # picked up: gone from where the map had it
        nav.attach(panel, "panel")
        grid = nav.costmap.grid
        assert not occupied(0.0, 1.0)
        # without layers (no localisation), today's map: every movable object where it is
        plain = Navigator(robot, world.obstacle_body_ids(), world.movable)
        grid = plain.costmap.grid
        assert occupied(0.0, -0.5) and occupied(-1.0, 1.0) and not occupied(0.0, 1.0)
