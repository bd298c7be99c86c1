"""The route graph of Nav2's route server: nodes (points of the world frame) joined by
directed edges, each with a cost and the polyline the robot drives along it.

A world names a graph in Nav2's GeoJSON format (``route_graph: FILE.geojson``: ``Point``
features are nodes, ``MultiLineString`` / ``LineString`` features with ``startid`` and
``endid`` are edges, driven straight from node to node as Nav2 does). Otherwise one is
generated from the world (:func:`graph_from_world`): a node in each doorway of its walls and
one at the centre of each room (the free point farthest from the walls), an edge both ways
between each doorway and the rooms on its two sides, along a path planned through free space.
"""

from __future__ import annotations

import heapq
import json
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

ROOM_MIN_AREA = 1.0
"""Free regions smaller than this (m^2) get no node of their own."""
DOOR_REACH = 1.5
"""How far (m) from a doorway its rooms are looked for, on each side of the wall."""
DENSITY = 0.05
"""Spacing (m) of the points of a straight GeoJSON edge."""


@dataclass(frozen=True)
class RouteNode:
    """A node of the graph: its id and position in the world frame."""

    id: int
    x: float
    y: float
    kind: str = ""
    """What the node stands for in a generated graph (``room`` or ``door``)."""


@dataclass(frozen=True, eq=False)
class RouteEdge:
    """A directed edge from node ``start`` to node ``end``: its cost (m) and the polyline
    (n, 2) of points the robot's turning point drives along."""

    id: int
    start: int
    end: int
    cost: float
    points: np.ndarray


@dataclass
class Route:
    """A route: the nodes from the start node to the goal node and the edges between them."""

    nodes: list[RouteNode]
    edges: list[RouteEdge]
    route_cost: float

    def points(self) -> np.ndarray:
        """The dense polyline (n, 2) from the first node to the last."""
        if not self.edges:
            n = self.nodes[0]
            return np.array([[n.x, n.y]])
        parts = [self.edges[0].points] + [e.points[1:] for e in self.edges[1:]]
        return np.vstack(parts)


@dataclass
class RouteGraph:
    """Nodes by id and the edges leaving each node."""

    nodes: dict[int, RouteNode] = field(default_factory=dict)
    edges: list[RouteEdge] = field(default_factory=list)
    source: str = "generated"

    def out_of(self, node: int) -> list[RouteEdge]:
        return [e for e in self.edges if e.start == node]

    def nearest(self, x: float, y: float) -> RouteNode | None:
        """The node nearest (x, y), None in an empty graph."""
        if not self.nodes:
            return None
        return min(self.nodes.values(), key=lambda n: (math.hypot(n.x - x, n.y - y), n.id))

    def route(self, start: int, goal: int,
              usable: Callable[[RouteEdge], bool] | None = None) -> Route | None:
        """The cheapest route from node ``start`` to node ``goal`` (Dijkstra on the edges'
        costs) over the edges ``usable`` accepts (all without it), None when the goal cannot
        be reached."""
        best = {start: 0.0}
        came: dict[int, RouteEdge] = {}
        queue = [(0.0, start)]
        done: set[int] = set()
        while queue:
            cost, node = heapq.heappop(queue)
            if node in done:
                continue
            done.add(node)
            if node == goal:
                break
            for edge in self.out_of(node):
                if usable is not None and not usable(edge):
                    continue
                new = cost + edge.cost
                if new < best.get(edge.end, math.inf):
                    best[edge.end] = new
                    came[edge.end] = edge
                    heapq.heappush(queue, (new, edge.end))
        if goal not in done:
            return None
        edges: list[RouteEdge] = []
        node = goal
        while node != start:
            edge = came[node]
            edges.append(edge)
            node = edge.start
        edges.reverse()
        nodes = [self.nodes[start]] + [self.nodes[e.end] for e in edges]
        return Route(nodes, edges, best[goal])


class GraphError(ValueError):
    """A route graph file that cannot be read."""


def _straight(a: RouteNode, b: RouteNode) -> np.ndarray:
    n = max(2, math.ceil(math.hypot(b.x - a.x, b.y - a.y) / DENSITY) + 1)
    t = np.linspace(0.0, 1.0, n)[:, None]
    return np.array([a.x, a.y]) * (1 - t) + np.array([b.x, b.y]) * t


def read_geojson(path: str | Path) -> RouteGraph:
    """The graph of a GeoJSON file in Nav2's route-graph format; :class:`GraphError` saying
    what is wrong otherwise."""
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise GraphError(f"{path}: {exc}") from None
    features = data.get("features") if isinstance(data, dict) else None
    if not isinstance(features, list):
        raise GraphError(f"{path}: not a GeoJSON FeatureCollection")
    graph = RouteGraph(source=str(path))
    pending: list[tuple[int, int, int, Any]] = []
    for k, feature in enumerate(features):
        geometry = (feature or {}).get("geometry") or {}
        props = (feature or {}).get("properties") or {}
        kind = geometry.get("type")
        try:
            if kind == "Point":
                x, y = (float(v) for v in geometry["coordinates"][:2])
                node_id = int(props["id"])
                graph.nodes[node_id] = RouteNode(node_id, x, y)
            elif kind in ("MultiLineString", "LineString"):
                pending.append((int(props["id"]), int(props["startid"]), int(props["endid"]),
                                props.get("cost")))
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise GraphError(f"{path}: feature {k}: {kind} without a usable {exc}") from None
    for edge_id, start, end, cost in pending:
        if start not in graph.nodes or end not in graph.nodes:
            raise GraphError(f"{path}: edge {edge_id} joins unknown nodes {start} -> {end}")
        points = _straight(graph.nodes[start], graph.nodes[end])
        length = float(np.sum(np.hypot(*np.diff(points, axis=0).T)))
        graph.edges.append(RouteEdge(edge_id, start, end,
                                     float(cost) if cost is not None else length, points))
    return graph


@dataclass(frozen=True)
class Doorway:
    """A doorway of a wall: its centre, the wall's direction and thickness, its width."""

    centre: tuple[float, float]
    along: tuple[float, float]
    width: float
    thickness: float


def doorways(walls: Iterable[Any]) -> list[Doorway]:
    """The doorways of the world's walls (:class:`~bt_manip.sim.world_spec.WallSpec`)."""
    out = []
    for wall in walls:
        (x0, y0), (x1, y1) = wall.start, wall.end
        length = math.hypot(x1 - x0, y1 - y0)
        if length <= 0:
            continue
        ux, uy = (x1 - x0) / length, (y1 - y0) / length
        for door in wall.doors:
            out.append(Doorway((x0 + ux * door.at, y0 + uy * door.at), (ux, uy), door.width,
                               wall.thickness))
    return out


Planner = Callable[[tuple[float, float], tuple[float, float]], "np.ndarray | None"]
"""Plans between two points of the world: the polyline (n, 2), or None without a way."""


def graph_from_world(grid: Any, free: np.ndarray, walls: Iterable[Any],
                     plan: Planner) -> RouteGraph:
    """The generated graph (module docstring) of a world whose occupancy ``grid``
    (:class:`~bt_manip.navigation.grid.OccupancyGrid`) has ``free`` cells (where the robot
    fits); ``plan`` gives the edges' polylines."""
    from scipy import ndimage  # slow to import: only when a graph is generated

    res = float(grid.resolution)
    closed = grid.occupied.copy()
    doors = doorways(walls)
    for door in doors:
        _close(grid, closed, door)
    labels, count = ndimage.label(~closed)
    border = set(np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0],
                                           labels[:, -1]]))) - {0}
    clearance = ndimage.distance_transform_edt(~closed) * res
    graph = RouteGraph()
    room_node: dict[int, int] = {}
    for label in range(1, count + 1):
        inside = (labels == label) & free
        if label in border or inside.sum() * res * res < ROOM_MIN_AREA:
            continue
        score = np.where(inside, clearance, -1.0)
        r, c = np.unravel_index(int(np.argmax(score)), score.shape)
        x, y = grid.cell_to_world(r + 0.5, c + 0.5)
        node = RouteNode(len(graph.nodes), float(x), float(y), "room")
        graph.nodes[node.id] = node
        room_node[label] = node.id
    for door in doors:
        sides = [_room_beside(grid, labels, door, s) for s in (1.0, -1.0)]
        rooms = [room_node[s] for s in sides if s in room_node]
        if len(rooms) != 2 or rooms[0] == rooms[1]:
            continue
        node = RouteNode(len(graph.nodes), door.centre[0], door.centre[1], "door")
        graph.nodes[node.id] = node
        for room in rooms:
            _join(graph, graph.nodes[room], node, plan)
    return graph


def _join(graph: RouteGraph, a: RouteNode, b: RouteNode, plan: Planner) -> None:
    """Edges both ways between ``a`` and ``b`` along a planned path (none without one)."""
    points = plan((a.x, a.y), (b.x, b.y))
    if points is None or len(points) < 2:
        return
    cost = float(np.sum(np.hypot(*np.diff(points, axis=0).T)))
    graph.edges.append(RouteEdge(len(graph.edges), a.id, b.id, cost, points))
    graph.edges.append(RouteEdge(len(graph.edges), b.id, a.id, cost, points[::-1].copy()))


def _close(grid: Any, occupied: np.ndarray, door: Doorway) -> None:
    """Mark the doorway's gap occupied (to tell the rooms apart)."""
    res = float(grid.resolution)
    ux, uy = door.along
    nx, ny = -uy, ux
    half_t = max(door.thickness / 2.0, res)
    for s in np.arange(-door.width / 2 - res, door.width / 2 + res, res / 2):
        for t in np.arange(-half_t, half_t + res / 4, res / 2):
            x = door.centre[0] + ux * s + nx * t
            y = door.centre[1] + uy * s + ny * t
            r, c = grid.world_to_cell(x, y)
            if 0 <= r < occupied.shape[0] and 0 <= c < occupied.shape[1]:
                occupied[r, c] = True


def _room_beside(grid: Any, labels: np.ndarray, door: Doorway, side: float) -> int:
    """The label of the free region on one side of the doorway (0: none within reach)."""
    ux, uy = door.along
    nx, ny = -uy * side, ux * side
    for d in np.arange(door.thickness / 2 + grid.resolution, DOOR_REACH, grid.resolution):
        r, c = grid.world_to_cell(door.centre[0] + nx * d, door.centre[1] + ny * d)
        if 0 <= r < labels.shape[0] and 0 <= c < labels.shape[1] and labels[r, c]:
            return int(labels[r, c])
    return 0
