"""Current Nav2's nodes (main branch, Kilted): ports, defaults, statuses and result codes.

Nodes that need no world run on a manual clock; the others in ``two_rooms.yaml`` (two rooms
joined by a doorway) and ``two_rooms_graph.yaml`` (the same with a GeoJSON route graph).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import bt_manip.nav2  # noqa: F401  (registers the Nav2 nodes)
from bt_manip.bt import Tree, TreeContext, load_tree_string
from bt_manip.bt.registry import registry
from bt_manip.clock import ManualClock
from bt_manip.nav2.path import Nav2Path
from bt_manip.nav2.route import ROUTE_RECOVERABLE, RouteError, route_goals
from bt_manip.nav2.route_graph import GraphError, Route, RouteGraph, RouteNode, read_geojson
from bt_manip.nav2.tracking import TrackingFeedback, tracking_feedback
from bt_manip.nav2.waypoints import WaypointState
from bt_manip.run.context import RunContext
from bt_manip.sim.world import World

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
MODELS = ROOT.parent / "shared" / "samples" / "nav2" / "main" / "nav2_tree_nodes.xml"
NEW_NODES = (
    "FollowPath", "RemovePassedGoals", "ValidatePath", "IsGoalNearby", "PathHandlerSelector",
    "IsWithinPathTrackingBounds", "PathExpiringTimer", "ProgressCheckerSelector",
    "ComputeRoute", "ExtractRouteNodesAsGoals", "GetNextFewGoals", "AppendGoalPoseToGoals",
    "WouldARouteRecoveryHelp", "GetCurrentPose", "GetPoseFromPath", "ArePosesNear",
    "ConcatenatePaths", "ComputePathThroughPoses",
)


def tree_of(body: str, bb: dict[str, object] | None = None,
            clock: ManualClock | None = None, world: World | None = None) -> Tree:
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="M">{body}</BehaviorTree></root>'
    context: Any = (RunContext.for_world(world) if world is not None
                    else TreeContext(clock=clock or ManualClock()))
    return load_tree_string(xml, context=context, blackboard=dict(bb or {}))


def line(n: int = 21, step: float = 0.5, y: float = 0.0) -> Nav2Path:
    xs = np.arange(n) * step
    return Nav2Path(np.column_stack([xs, np.full(n, y), np.zeros(n)]), length=xs[-1])


# -- ports and defaults, against Nav2's own model file ----------------------------------

@pytest.mark.skipif(not MODELS.is_file(), reason=f"Nav2's model file is not at {MODELS}")
@pytest.mark.parametrize("node_id", NEW_NODES)
def test_ports_and_defaults_are_nav2s(node_id: str) -> None:
    model = next(e for e in ET.parse(MODELS).getroot().iter() if e.get("ID") == node_id)
    cls = registry.get(node_id)
    ours = {**cls.INPUT_PORTS, **cls.OUTPUT_PORTS}
    for port in model:
        name = port.get("name")
        assert name in ours, f"{node_id} lacks Nav2's port {name}"
        default = port.get("default")
        if default is not None and default != '""':
            value = ours[name].default_value
            assert str(value).lower() == default.strip('"').lower() or (
                isinstance(value, float) and float(default) == value
            ), f"{node_id}.{name}: default {value!r}, Nav2's {default}"
        direction = cls.OUTPUT_PORTS if port.tag == "output_port" else cls.INPUT_PORTS
        assert name in direction, f"{node_id}.{name} is not an {port.tag}"


# -- nodes without a world ---------------------------------------------------------------

def test_selectors_write_their_default() -> None:
    tree = tree_of('<Sequence><ProgressCheckerSelector selected_progress_checker="{p}" '
                   'default_progress_checker="progress_checker"/><PathHandlerSelector '
                   'selected_path_handler="{h}" default_path_handler="PathHandler"/></Sequence>')
    assert tree.tick().value == "SUCCESS"
    assert tree.blackboard.get("p") == "progress_checker"
    assert tree.blackboard.get("h") == "PathHandler"
    assert tree_of('<PathHandlerSelector selected_path_handler="{h}"/>').tick().value == (
        "FAILURE")


def test_path_expiring_timer_counts_from_the_last_new_path() -> None:
    clock = ManualClock()
    path = line()
    tree = tree_of('<PathExpiringTimer seconds="2" path="{path}"/>', {"path": path}, clock)
    assert tree.tick().value == "FAILURE"  # the first tick starts the timer
    clock.advance(1.5)
    assert tree.tick().value == "FAILURE"
    tree.blackboard.set("path", line())  # a new path restarts it
    clock.advance(1.0)
    assert tree.tick().value == "FAILURE"  # 2.5 s after the start, but the path is new
    clock.advance(1.5)
    assert tree.tick().value == "FAILURE"
    clock.advance(0.5)
    assert tree.tick().value == "SUCCESS"  # 2 s since the new path; then it starts again
    clock.advance(0.5)
    assert tree.tick().value == "FAILURE"


def test_tracking_feedback_is_signed_left_positive() -> None:
    pts = np.array([[0.0, 0.0], [2.0, 0.0], [4.0, 0.0]])
    left = tracking_feedback(pts, (4.0, 0.0, 0.0), (1.0, 0.3), (1.0, 0.3, 0.2))
    assert left.position_tracking_error == pytest.approx(0.3)
    assert left.heading_tracking_error == pytest.approx(0.2)
    assert left.remaining_path_length == pytest.approx(3.0)
    assert left.current_path_index == 0
    right = tracking_feedback(pts, (4.0, 0.0, 0.0), (3.0, -0.4), (3.0, -0.4, 0.0))
    assert right.position_tracking_error == pytest.approx(-0.4)
    assert right.current_path_index == 1


@pytest.mark.parametrize(("error", "heading", "expected"), [
    (0.0, 0.0, "SUCCESS"), (0.25, 0.0, "FAILURE"), (-0.25, 0.0, "SUCCESS"),
    (-0.35, 0.0, "FAILURE"), (0.1, 1.5, "FAILURE"),
])
def test_within_path_tracking_bounds_by_side(error: float, heading: float,
                                             expected: str) -> None:
    feedback = TrackingFeedback(position_tracking_error=error, heading_tracking_error=heading)
    tree = tree_of('<IsWithinPathTrackingBounds max_error_left="0.2" max_error_right="0.3" '
                   'max_error_heading="1.0" tracking_feedback="{fb}"/>', {"fb": feedback})
    assert tree.tick().value == expected


def test_within_path_tracking_bounds_without_feedback_succeeds() -> None:
    assert tree_of("<IsWithinPathTrackingBounds/>").tick().value == "SUCCESS"


def test_pose_and_path_nodes() -> None:
    first, second = line(5), line(3, y=1.0)
    tree = tree_of(
        '<Sequence><GetPoseFromPath path="{a}" index="-1" pose="{last}"/>'
        '<GetPoseFromPath path="{a}" pose="{start}"/>'
        '<ConcatenatePaths input_path1="{a}" input_path2="{b}" output_path="{ab}"/>'
        '<ArePosesNear ref_pose="{last}" target_pose="{near}" tolerance="0.3"/></Sequence>',
        {"a": first, "b": second, "near": (2.1, 0.1, 0.0)},
    )
    assert tree.tick().value == "SUCCESS"
    assert tree.blackboard.get("last") == (2.0, 0.0, 0.0)
    assert tree.blackboard.get("start") == (0.0, 0.0, 0.0)
    ab = tree.blackboard.get("ab")
    assert len(ab) == 8 and ab.length == pytest.approx(2.0 + 1.0 + math.hypot(2.0, 1.0))
    assert tree_of('<GetPoseFromPath path="{a}" index="5" pose="{p}"/>',
                   {"a": first}).tick().value == "FAILURE"
    assert tree_of('<ArePosesNear ref_pose="{a}" target_pose="{b}"/>',  # default 0.5 m
                   {"a": (0.0, 0.0, 0.0), "b": (0.6, 0.0, 0.0)}).tick().value == "FAILURE"
    assert tree_of('<ConcatenatePaths input_path1="{a}" input_path2="{b}" output_path="{c}"/>',
                   {"a": first}).tick().value == "FAILURE"


def test_goal_list_nodes() -> None:
    tree = tree_of(
        '<Sequence><AppendGoalPoseToGoals input_goals="{goals}" goal_pose="{goal}" '
        'output_goals="{all}"/><GetNextFewGoals input_goals="{all}" num_goals="2" '
        'output_goals="{next}"/><GetNextFewGoals input_goals="{all}" num_goals="9" '
        'output_goals="{every}"/></Sequence>',
        {"goals": "1;0;0|2;0;0", "goal": "3;1;1.5"},
    )
    assert tree.tick().value == "SUCCESS"
    assert tree.blackboard.get("all") == [(1.0, 0.0, 0.0), (2.0, 0.0, 0.0), (3.0, 1.0, 1.5)]
    assert tree.blackboard.get("next") == [(1.0, 0.0, 0.0), (2.0, 0.0, 0.0)]
    assert len(tree.blackboard.get("every")) == 3


def test_would_a_route_recovery_help_codes() -> None:
    assert {int(c) for c in ROUTE_RECOVERABLE} == {400, 404, 405}
    for code, expected in ((400, "SUCCESS"), (404, "SUCCESS"), (405, "SUCCESS"),
                           (402, "FAILURE"), (403, "FAILURE"), (0, "FAILURE")):
        tree = tree_of(f'<WouldARouteRecoveryHelp error_code="{code}"/>')
        assert tree.tick().value == expected, code
    assert RouteError.NO_VALID_GRAPH == 402 and RouteError.INDETERMINANT_NODES_ON_GRAPH == 403


def test_route_graph_dijkstra_and_goals() -> None:
    graph = read_geojson(HERE / "two_rooms.geojson")
    assert sorted(graph.nodes) == [10, 11, 12]
    route = graph.route(10, 12)
    assert route is not None
    assert [n.id for n in route.nodes] == [10, 11, 12]
    assert route.route_cost == pytest.approx(2.0 + 7.5)  # the given cost, else the length
    assert graph.route(12, 10) is None  # edges are directed
    goals = route_goals(route)
    assert goals == [(-2.0, 0.5, 0.0), (0.0, 0.5, 0.0), (2.0, 0.5, 0.0)]
    pts = route.points()
    assert tuple(pts[0]) == (-2.0, 0.5) and tuple(pts[-1]) == (2.0, 0.5)


def test_bad_geojson_names_the_problem(tmp_path: Path) -> None:
    bad = tmp_path / "g.geojson"
    bad.write_text('{"type": "FeatureCollection", "features": [{"geometry": {"type": '
                   '"LineString"}, "properties": {"id": 1, "startid": 1, "endid": 2}}]}')
    with pytest.raises(GraphError, match="edge 1 joins unknown nodes"):
        read_geojson(bad)
    bad.write_text("[")
    with pytest.raises(GraphError):
        read_geojson(bad)


def test_extract_route_nodes_as_goals() -> None:
    route = Route([RouteNode(0, 0.0, 0.0), RouteNode(1, 0.0, 2.0)], [], 2.0)
    tree = tree_of('<ExtractRouteNodesAsGoals route="{route}" goals="{goals}"/>',
                   {"route": route})
    assert tree.tick().value == "SUCCESS"
    assert tree.blackboard.get("goals") == [(0.0, 0.0, math.pi / 2), (0.0, 2.0, math.pi / 2)]
    assert tree_of('<ExtractRouteNodesAsGoals route="{r}" goals="{g}"/>').tick().value == (
        "FAILURE")
    assert RouteGraph().nearest(0.0, 0.0) is None


# -- nodes in a world --------------------------------------------------------------------

@pytest.fixture(scope="module")
def rooms() -> Any:
    with World(HERE / "two_rooms.yaml", seed=0) as world:
        yield world


def test_generated_graph_has_rooms_and_the_doorway(rooms: World) -> None:
    tree = tree_of('<ComputeRoute goal="east" use_poses="true" route="{route}" path="{path}" '
                   'error_code_id="{code}"/>', world=rooms)
    assert tree.tick().value == "SUCCESS"
    route = tree.blackboard.get("route")
    assert [n.kind for n in route.nodes] == ["room", "door", "room"]
    assert route.nodes[1].x == pytest.approx(0.0) and route.nodes[1].y == pytest.approx(0.5)
    assert route.nodes[0].x < 0 < route.nodes[2].x
    path = tree.blackboard.get("path")
    assert isinstance(path, Nav2Path) and len(path) > 10
    assert tree.blackboard.get("code") == 0


def test_compute_route_by_ids_and_its_codes(rooms: World) -> None:
    tree = tree_of('<ComputeRoute start_id="0" goal_id="99" route="{r}" path="{p}" '
                   'error_code_id="{code}" error_msg="{msg}"/>', world=rooms)
    assert tree.tick().value == "FAILURE"
    assert tree.blackboard.get("code") == 403
    assert "99" in tree.blackboard.get("msg")
    tree = tree_of('<ComputeRoute start_id="0" goal_id="0" route="{r}" path="{p}"/>',
                   world=rooms)
    assert tree.tick().value == "SUCCESS"
    assert len(tree.blackboard.get("r").nodes) == 1


def test_validate_path_and_goal_nearby(rooms: World) -> None:
    free = line(7, step=0.25)  # base poses from x=0 .. 1.5 along y=0: through the wall
    clear = Nav2Path(free.poses + np.array([-3.0, 0.0, 0.0]), length=free.length)
    tree = tree_of('<ValidatePath path="{p}" collision_poses="{c}"/>', {"p": clear},
                   world=rooms)
    assert tree.tick().value == "SUCCESS" and tree.blackboard.get("c") == []
    blocked = Nav2Path(free.poses + np.array([-1.0, -1.5, 0.0]), length=free.length)
    tree = tree_of('<ValidatePath path="{p}" collision_poses="{c}" '
                   'stop_at_first_collision="false"/>', {"p": blocked}, world=rooms)
    assert tree.tick().value == "FAILURE"
    assert len(tree.blackboard.get("c")) >= 2  # the crate at (-1, -1.5)
    near = tree_of('<IsGoalNearby path="{p}" proximity_threshold="2.0"/>', {"p": clear},
                   world=rooms)
    assert near.tick().value == "SUCCESS"  # 1.5 m left from the robot's nearest pose
    far = tree_of('<IsGoalNearby path="{p}"/>', {"p": clear}, world=rooms)
    assert far.tick().value == "FAILURE"  # default 1.0 m


def test_current_pose_and_remove_passed_goals_statuses(rooms: World) -> None:
    tree = tree_of(
        '<Sequence><GetCurrentPose current_pose="{here}"/><RemovePassedGoals '
        'input_goals="{goals}" output_goals="{left}" radius="0.7" '
        'input_waypoint_statuses="{st}" output_waypoint_statuses="{st}"/></Sequence>',
        {"goals": "-2.4;0;0|2;0;0"}, world=rooms,
    )
    assert tree.tick().value == "SUCCESS"
    x, y, _ = tree.blackboard.get("here")
    assert (x, y) == pytest.approx((-2.5, 0.0), abs=0.05)
    assert tree.blackboard.get("left") == [(2.0, 0.0, 0.0)]
    states = [s.waypoint_status for s in tree.blackboard.get("st")]
    assert states == [WaypointState.COMPLETED, WaypointState.PENDING]


def test_a_plan_through_every_goal_reports_all_goals_reached(rooms: World) -> None:
    tree = tree_of('<ComputePathThroughPoses goals="{goals}" path="{path}" '
                   'last_reached_index="{last}" error_code_id="{code}"/>',
                   {"goals": "-1.5;0;0|2;0;0", "last": 7}, world=rooms)
    assert tree.tick().value == "SUCCESS"
    assert tree.blackboard.get("last") == -1  # ALL_GOALS
    assert tree.blackboard.get("code") == 0


def test_a_world_names_its_geojson_graph() -> None:
    with World(HERE / "two_rooms_graph.yaml", seed=0) as world:
        tree = tree_of('<ComputeRoute goal="{g}" use_poses="true" route="{r}" path="{p}"/>',
                       {"g": "2.1;0.4;0"}, world=world)
        assert tree.tick().value == "SUCCESS"
        assert [n.id for n in tree.blackboard.get("r").nodes] == [10, 11, 12]
