"""Nav2's route-server nodes: ComputeRoute, ExtractRouteNodesAsGoals and
WouldARouteRecoveryHelp, on the world's route graph (:mod:`bt_manip.nav2.route_graph`)."""

from __future__ import annotations

import enum
import math
import weakref
from typing import Any

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction, WorldAccess
from bt_manip.behaviours.navigate import synced_navigator
from bt_manip.bt.node import PortError, SyncActionNode
from bt_manip.bt.ports import Port
from bt_manip.bt.registry import registry
from bt_manip.nav2.actions import PlanAction, error_ports
from bt_manip.nav2.conditions import _WouldARecoveryHelp
from bt_manip.nav2.path import Nav2Path, Pose2D, goal_pose, path_from_points
from bt_manip.nav2.path_checks import in_collision
from bt_manip.nav2.route_graph import (
    GraphError,
    Route,
    RouteEdge,
    RouteGraph,
    graph_from_world,
    read_geojson,
)


class RouteError(enum.IntEnum):
    """ComputeRoute result codes."""

    NONE = 0
    UNKNOWN = 400
    TF_ERROR = 401
    NO_VALID_GRAPH = 402
    INDETERMINANT_NODES_ON_GRAPH = 403
    TIMEOUT = 404
    NO_VALID_ROUTE = 405
    OPERATION_FAILED = 406


ROUTE_RECOVERABLE = frozenset({RouteError.UNKNOWN, RouteError.NO_VALID_ROUTE,
                               RouteError.TIMEOUT})
"""Route failures that a recovery may cure (WouldARouteRecoveryHelp)."""

_GRAPHS: weakref.WeakKeyDictionary[Any, RouteGraph] = weakref.WeakKeyDictionary()
"""The graph of each navigator (one per robot and run), built on first use."""


def route_graph(node: WorldAccess, robot: Any) -> RouteGraph:
    """The route graph of the run's world for ``robot``: the world's GeoJSON file when it
    names one, else the graph generated from the world (with the robot's footprint)."""
    nav = synced_navigator(node, robot)
    graph = _GRAPHS.get(nav)
    if graph is not None:
        return graph
    spec = node.world.spec
    if spec.route_graph is not None:
        try:
            graph = read_geojson(spec.route_graph)
        except GraphError as exc:
            raise ActionFailed(str(exc)) from None
    else:
        nav.refresh()

        def plan(a: tuple[float, float], b: tuple[float, float]) -> np.ndarray | None:
            result = nav.plan_to((*a, 0.0), (*b, 0.0))
            return result.polyline if result.ok else None

        graph = graph_from_world(nav.costmap.grid, np.isfinite(nav.cost), spec.walls, plan)
    _GRAPHS[nav] = graph
    return graph


def route_path(route: Route, pivot: float) -> Nav2Path:
    """The dense path along ``route``: poses of the base frame whose turning point drives the
    edges' polylines; it ends on the last node, facing along the last edge."""
    points = route.points()
    if len(points) > 1:
        d = points[-1] - points[-2]
        yaw = math.atan2(float(d[1]), float(d[0]))
    else:
        yaw = 0.0
    end = points[-1]
    goal = (float(end[0]) - pivot * math.cos(yaw), float(end[1]) - pivot * math.sin(yaw), yaw)
    return path_from_points(points, goal, pivot)


@registry.register
class ComputeRoute(PlanAction):
    """Finds the cheapest route on the world's route graph, within the tick.

    With ``use_poses`` the route goes from the node nearest the start (the robot, or
    ``start`` with ``use_start``) to the node nearest ``goal``, as Nav2's route server picks
    them; otherwise from node ``start_id`` to node ``goal_id``. Edges are scored as Nav2's
    CostmapScorer does with ``invalid_on_collision`` and ``invalid_off_map``: an edge along
    which the robot's footprint would touch an obstacle of its costmap as it is now (the
    movable objects drawn in), or leave the map, is not taken.

    - SUCCESS: ``route`` holds the :class:`~bt_manip.nav2.route_graph.Route` (nodes, edges,
      cost), ``path`` the dense path along its edges from the first node to the last,
      ``planning_time`` 0 (no sim time passes), ``error_code_id`` 0;
    - FAILURE: 402 NO_VALID_GRAPH (no graph, or one without nodes), 403
      INDETERMINANT_NODES_ON_GRAPH (a node id not in the graph, or a pose that cannot be
      read), 405 NO_VALID_ROUTE (the goal node cannot be reached on the usable edges), with
      the reason in ``error_msg``.
    """

    UNKNOWN = RouteError.UNKNOWN
    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "start": PortInformation(object, False, "Start pose (used with use_start)"),
        "goal": PortInformation(object, False, "Goal pose (used with use_poses)"),
        "start_id": Port(int, False, "Start node ID to use", 0),
        "goal_id": Port(int, False, "Goal node ID to use", 0),
        "use_start": PortInformation(bool, False, "Whether to use the start or the robot's "
                                     "pose", False),
        "use_poses": PortInformation(bool, False, "Whether to use the start and goal poses or "
                                     "the start and goal node IDs", False),
        "server_name": PortInformation(str, False, "Action server name", "compute_route"),
        "server_timeout": PortInformation(float, False, "Action server timeout (ms)", 20.0),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "route": PortInformation(Route, False, "Route created by ComputeRoute"),
        "path": PortInformation(Nav2Path, False, "Path created by ComputeRoute"),
        "planning_time": PortInformation(float, False, "Time it took to compute the route (s)"),
        **error_ports("Compute route"),
    }

    def _ends(self, graph: RouteGraph, robot: Any) -> tuple[int, int]:
        if not bool(self.get_input("use_poses")):
            ids = int(self.get_input("start_id")), int(self.get_input("goal_id"))
            for which, node_id in zip(("start", "goal"), ids, strict=True):
                if node_id not in graph.nodes:
                    self.fail(RouteError.INDETERMINANT_NODES_ON_GRAPH,
                              f"{which} node {node_id} is not in the route graph")
            return ids
        try:
            start: Pose2D = (goal_pose(self.world, self.get_input("start"))
                             if bool(self.get_input("use_start")) else self.believed_pose(robot))
            goal = goal_pose(self.world, self.get_input("goal"))
        except (ActionFailed, PortError) as exc:
            self.fail(RouteError.INDETERMINANT_NODES_ON_GRAPH, str(exc))
        first, last = graph.nearest(start[0], start[1]), graph.nearest(goal[0], goal[1])
        assert first is not None and last is not None
        return first.id, last.id

    def begin(self) -> None:
        robot = self.base()
        graph = route_graph(self, robot)
        if not graph.nodes:
            self.fail(RouteError.NO_VALID_GRAPH, "the route graph has no nodes")
        start, goal = self._ends(graph, robot)
        nav = synced_navigator(self, robot)
        nav.refresh()
        blocked: list[int] = []

        def usable(edge: RouteEdge) -> bool:
            if in_collision(nav, edge.points)[0].any():
                blocked.append(edge.id)
                return False
            return True

        route = graph.route(start, goal, usable)
        if route is None:
            why = f" ({len(blocked)} edge(s) blocked on the costmap)" if blocked else ""
            self.fail(RouteError.NO_VALID_ROUTE,
                      f"no route from node {start} to node {goal} on the graph{why}")
        self.set_output("route", route)
        self.set_output("path", route_path(route, nav.pivot))
        self.set_output("planning_time", 0.0)


@registry.register
class ExtractRouteNodesAsGoals(WorldAccess, SyncActionNode):
    """Writes the nodes of ``route`` to ``goals``, as poses facing along the route towards the
    next node (the last one facing along its edge): SUCCESS; FAILURE without a route."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "route": PortInformation(Route, True, "Route to convert its nodes into goals"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "goals": PortInformation(object, False, "Goals of the route's nodes"),
    }

    def update(self) -> Status:
        route = self.get_input("route", None)
        if not isinstance(route, Route) or not route.nodes:
            self.feedback_message = f"no route to take nodes from (got {route!r})"
            return Status.FAILURE
        self.feedback_message = ""
        self.set_output("goals", route_goals(route))
        return Status.SUCCESS


def route_goals(route: Route) -> list[Pose2D]:
    """The route's nodes as poses facing the next node (the last, the one before)."""
    nodes = route.nodes
    goals: list[Pose2D] = []
    for k, node in enumerate(nodes):
        a, b = (node, nodes[k + 1]) if k + 1 < len(nodes) else (nodes[k - 1] if k else node,
                                                                  node)
        yaw = math.atan2(b.y - a.y, b.x - a.x) if (a is not b) else 0.0
        goals.append((node.x, node.y, yaw))
    return goals


@registry.register
class WouldARouteRecoveryHelp(_WouldARecoveryHelp):
    """SUCCESS when ``error_code`` is a route failure that a recovery may cure (400 UNKNOWN,
    404 TIMEOUT, 405 NO_VALID_ROUTE), FAILURE otherwise."""

    CODES = ROUTE_RECOVERABLE
