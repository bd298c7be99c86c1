"""Regions of the world named by a body, and points computed from them.

A region is the box of a named body of the world (a bin, a tray, a table), taken in the body's
own frame: for a body built of boxes, cylinders and spheres (furniture and objects of a world
file) it is the smallest box around its parts in that frame, so a bin turned on the table gives
a region turned with it; for any other body (a URDF with links or meshes) it is the body's
world axis-aligned bounding box. :class:`~bt_manip.behaviours.conditions.ObjectInRegion`
checks against the same region, so a point computed here lies in what it calls "inside".

Nodes:

- ``DropPoint``: the centre of one cell of a ``rows`` x ``cols`` grid laid over the top of a
  region (inset by ``margin``), ``clearance`` metres above its top: where to let go of an
  object so that it falls into a bin, each object on its own spot. Given a ``robot``, the cell
  is one its arm reaches (:mod:`bt_manip.manipulation.reach`): the asked one when it can, else
  the nearest one it can, else one it reaches with the tool tilted within ``max_tilt``.

Only DropPoint picks a point in a region; :class:`~bt_manip.behaviours.conditions.ObjectInRegion`
reads the region to test a point, not to choose one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pybullet as pb
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import FAILS, ActionFailed, WorldAccess, failure_reason
from bt_manip.bt import SyncActionNode, registry
from bt_manip.bt.node import closest
from bt_manip.bt.ports import NON_NEGATIVE, Accepts, Port, count_of
from bt_manip.geometry import quat_from_matrix, rotation_matrix
from bt_manip.manipulation.collision_scene import named_contacts
from bt_manip.manipulation.reach import Reached, ReachOptions, UnreachableError, first_reached
from bt_manip.sim import pybullet_queries as pbq

MAX_CELLS_PER_SIDE = 100
"""Largest number of rows or columns of a grid."""
MAX_CLEARANCE = 2.0
"""Highest a point may be above its region (m)."""
MAX_REACH_CELLS = 16
"""Cells of a grid (the asked one and the nearest others) a robot's reach is checked at."""
MAX_TILT = 60.0
"""Largest ``max_tilt`` of DropPoint (deg)."""
TILT_STEPS = 5
"""Even steps of the tool's tilt up to ``max_tilt`` that DropPoint tries."""
TOOL_DOWN = [0.0, 1.0, 0.0, 0.0]
"""The tool pointing straight down (quaternion x;y;z;w): MoveToPose's default orientation."""


@dataclass(frozen=True)
class Region:
    """A box in the world: ``lower``/``upper`` corners in the frame ``pose`` (a 4x4 world
    transform)."""

    name: str
    pose: np.ndarray
    lower: np.ndarray
    upper: np.ndarray

    @property
    def size(self) -> np.ndarray:
        """Extents (x, y, z) of the box in its frame."""
        extent: np.ndarray = self.upper - self.lower
        return extent

    def to_world(self, local: np.ndarray) -> np.ndarray:
        """A point of the region's frame in world coordinates."""
        world: np.ndarray = self.pose[:3, :3] @ local + self.pose[:3, 3]
        return world

    def to_local(self, point: np.ndarray) -> np.ndarray:
        """A world point in the region's frame."""
        offset = np.asarray(point, dtype=float) - self.pose[:3, 3]
        local: np.ndarray = self.pose[:3, :3].T @ offset
        return local

    def contains(self, point: np.ndarray) -> bool:
        """Whether a world point lies in the box (its faces included)."""
        local = self.to_local(point)
        return bool(np.all(self.lower <= local) and np.all(local <= self.upper))


_HALF_EXTENTS = {
    pb.GEOM_BOX: lambda d: (d[0] / 2, d[1] / 2, d[2] / 2),
    pb.GEOM_CYLINDER: lambda d: (d[1], d[1], d[0] / 2),  # (height, radius)
    pb.GEOM_CAPSULE: lambda d: (d[1], d[1], d[0] / 2 + d[1]),
    pb.GEOM_SPHERE: lambda d: (d[0], d[0], d[0]),
}


def region_of(world: Any, name: str) -> Region:
    """The region of the body ``name`` of ``world``; ActionFailed naming the known bodies when
    there is none."""
    try:
        body = world.body_id(name)
    except KeyError:
        known = sorted(world.infos)
        raise ActionFailed(
            f"no body named '{name}' in {world.path.name}{closest(name, set(known))}; "
            f"bodies: {', '.join(known) or 'none'}"
        ) from None
    client = world.client
    local = _local_box(client, body)
    if local is not None:
        pos, quat = pb.getBasePositionAndOrientation(body, physicsClientId=client)
        pose = np.eye(4)
        pose[:3, :3] = rotation_matrix(quat)
        pose[:3, 3] = pos
        return Region(name, pose, local[0], local[1])
    boxes = [pbq.aabb(client, body, link) for link in range(-1, pb.getNumJoints(
        body, physicsClientId=client))]
    lower = np.min([b[0] for b in boxes], axis=0)
    upper = np.max([b[1] for b in boxes], axis=0)
    return Region(name, np.eye(4), np.asarray(lower, float), np.asarray(upper, float))


def _local_box(client: int, body: int) -> tuple[np.ndarray, np.ndarray] | None:
    """The box around a single-link body's primitive shapes in its base frame, or None when
    the body has links or shapes of other kinds."""
    if pb.getNumJoints(body, physicsClientId=client) > 0:
        return None
    shapes = pbq.collision_shapes(client, body, -1)
    if not shapes or any(s.geometry_type not in _HALF_EXTENTS for s in shapes):
        return None
    corners = []
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    for s in shapes:
        half = np.asarray(_HALF_EXTENTS[s.geometry_type](s.dimensions), dtype=float)
        rot = rotation_matrix(s.local_orientation)
        corners.append((signs * half) @ rot.T + np.asarray(s.local_position, dtype=float))
    points = np.vstack(corners)
    return points.min(axis=0), points.max(axis=0)


def grid_cell(
    region: Region, index: int, rows: int, cols: int, margin: float, clearance: float
) -> np.ndarray:
    """World point over cell ``index`` of a ``rows`` x ``cols`` grid on top of ``region``.

    The grid covers the region's box seen from above, inset by ``margin`` on every side;
    columns run along the region's x axis and rows along its y axis, and cells are counted
    row by row from the corner of lowest x and y. The point is the cell's centre, ``clearance``
    above the top of the box. ActionFailed when ``index`` is not a cell of the grid or the
    margin leaves no room.
    """
    cells = rows * cols
    if not 0 <= index < cells:
        raise ActionFailed(
            f"index {index} is not a cell of the {rows} x {cols} grid over '{region.name}' "
            f"(0..{cells - 1})"
        )
    lo = region.lower[:2] + margin
    width = region.size[:2] - 2.0 * margin
    if np.any(width <= 0.0):
        raise ActionFailed(
            f"margin {margin:g} m leaves no room inside '{region.name}' "
            f"({region.size[0]:.3f} x {region.size[1]:.3f} m)"
        )
    col, row = index % cols, index // cols
    local = np.array([
        lo[0] + (col + 0.5) * width[0] / cols,
        lo[1] + (row + 0.5) * width[1] / rows,
        region.upper[2] + clearance,
    ])
    return region.to_world(local)


@registry.register
class DropPoint(WorldAccess, SyncActionNode):
    """Computes where to let go of an object over a region: the centre of cell ``index`` of a
    ``rows`` x ``cols`` grid laid over the top of ``region`` (a body of the world, e.g. the
    ``bin``), inset by ``margin`` from its sides, ``clearance`` metres above its top.

    The region is the body's box in its own frame, so the grid turns with a turned bin; the
    columns run along the body's x axis, the rows along its y axis, and cells are counted row
    by row from the corner of lowest x and y (``index`` 0 .. rows x cols - 1). ``point`` is
    written as a list x;y;z (world), ready for ``MoveToPose position="{point}"``.

    Without a ``robot`` (the default) the point is that of cell ``index``, whether an arm
    reaches it or not. With one, it is a point that robot's arm reaches with its grasp frame,
    checked by inverse kinematics from where the arm is (the solver MoveToPose uses) and in
    the arm's planning scene (the arm must not touch furniture, walls or floor there):

    1. cell ``index`` with the tool at ``orientation`` (MoveToPose's port and default: pointing
       down), when the arm reaches it;
    2. else the nearest cell it reaches with that orientation: the other cells by their
       distance from cell ``index``; of cells equally near, the one with fewer movable objects
       lying in the region under it first (each object on its own spot as far as can be),
       then the lower cell number (at most the :data:`MAX_REACH_CELLS` nearest cells are
       tried);
    3. else the tool tilted from ``orientation`` in five even steps up to ``max_tilt``
       degrees, the wrist toward the robot (the tool axis leaning away from it, as a hand
       reaching over a box's far edge), the smallest tilt first and each tilt over the cells in
       the order of 2.

    ``tool_orientation`` gets the orientation used (``orientation`` itself unless tilted), for
    ``MoveToPose orientation="{...}"``; ``cell`` the cell chosen and ``tilt`` the tilt (deg).

    - SUCCESS with ``point`` (and ``tool_orientation``, ``cell``, ``tilt``) written;
    - FAILURE (reason in the feedback) when ``region`` names no body of the world, ``index``
      is not a cell of the grid (or not a whole number), the margin leaves no room, a value
      read from the blackboard breaks its port's rule, ``robot`` names no robot of the world,
      or, with a robot, no cell tried is reached within ``max_tilt``: the reason gives the
      best IK error met, at which cell and tilt (or IK's reason when every cell is beyond
      reach).
    It finishes within its tick (never RUNNING), so there is nothing to halt.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "region": PortInformation(str, True, "body of the world whose box is the region (bin)"),
        "index": Port(int, True, "cell number, row by row from the lowest x and y", None,
                      NON_NEGATIVE),
        "rows": Port(int, False, "cells along the region's y axis", 3,
                     Accepts(1, MAX_CELLS_PER_SIDE)),
        "cols": Port(int, False, "cells along the region's x axis", 3,
                     Accepts(1, MAX_CELLS_PER_SIDE)),
        "margin": Port(float, False, "inset of the grid from each side of the region (m)", 0.02,
                       Accepts(0, 1)),
        "clearance": Port(float, False, "height of the point above the region's top (m)", 0.06,
                          Accepts(0, MAX_CLEARANCE)),
        "robot": PortInformation(
            str, False, "robot whose arm must reach the point (empty: none, the cell as asked)",
            "",
        ),
        "orientation": Port(
            list[float], False, "with a robot: the tool's orientation at the point, quaternion "
            "x;y;z;w (world), as MoveToPose's", list(TOOL_DOWN), count_of(4),
        ),
        "max_tilt": Port(
            float, False, "with a robot: how far the tool may tilt from orientation, the wrist "
            "toward the robot, when no cell is reached without (deg)", 25.0,
            Accepts(0, MAX_TILT),
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "point": PortInformation(list[float], False, "the drop point x;y;z (m, world)"),
        "tool_orientation": PortInformation(
            list[float], False, "the tool's orientation there, quaternion x;y;z;w (world): "
            "orientation, or orientation tilted"
        ),
        "cell": PortInformation(int, False, "the cell of the point"),
        "tilt": PortInformation(float, False, "the tool's tilt from orientation (deg)"),
    }

    def update(self) -> Status:
        try:
            region = region_of(self.world, self.get_input("region"))
            index = self.get_input("index")
            if index != int(index):  # a script's number from the blackboard
                raise ActionFailed(f"index must be a whole number, got {index}")
            rows, cols = int(self.get_input("rows")), int(self.get_input("cols"))
            margin, clearance = float(self.get_input("margin")), float(self.get_input("clearance"))
            point = grid_cell(region, int(index), rows, cols, margin, clearance)
            orientation = [float(v) for v in self.get_input("orientation")]
            cell, tilt = int(index), 0.0
            if self.get_input("robot"):
                cells = _nearest_cells(self.world, region, int(index), rows, cols, margin,
                                       clearance)
                reached = self._reach(region, cells, orientation)
                cell, point = cells[reached.index]
                tilt = math.degrees(reached.tilt)
                if reached.tilt > 0.0:
                    orientation = [float(v) for v in quat_from_matrix(reached.rotation)]
        except FAILS as exc:
            self.feedback_message = failure_reason(exc)
            return Status.FAILURE
        self.feedback_message = ""
        self.set_output("point", [float(v) for v in point])
        self.set_output("tool_orientation", orientation)
        self.set_output("cell", cell)
        self.set_output("tilt", tilt)
        return Status.SUCCESS

    def _reach(self, region: Region, cells: list[tuple[int, np.ndarray]],
               orientation: list[float]) -> Reached:
        """The first of ``cells`` the robot's arm reaches (see the class docstring)."""
        robot = self.robot()
        planner = self.arm_planner()
        scene = planner.scene()
        seed = robot.arm_positions()
        planner.sync(scene, "", (seed,), movables=False)

        def free(q: np.ndarray) -> str | None:
            if not scene.collides(q):
                return None
            return named_contacts(scene.contacts(q), 3)

        rows = int(self.get_input("rows"))
        cols = int(self.get_input("cols"))
        options = ReachOptions(math.radians(float(self.get_input("max_tilt"))), TILT_STEPS)
        try:
            return first_reached(
                self.services(), robot.description.grasp_frame, [p for _, p in cells],
                rotation_matrix(orientation), seed, options, free,
                lambda i: f"cell {cells[i][0]}",
            )
        except UnreachableError as exc:
            tried = f" (the {len(cells)} nearest tried)" if len(cells) < rows * cols else ""
            raise ActionFailed(
                f"{self.robot_name_of(robot)} reaches no cell of the {rows} x {cols} grid over "
                f"'{region.name}'{tried}: {exc}"
            ) from None


def _nearest_cells(world: Any, region: Region, index: int, rows: int, cols: int,
                   margin: float, clearance: float) -> list[tuple[int, np.ndarray]]:
    """Cell ``index`` and the other cells of the grid by their distance from it, equal
    distances by the objects lying in them (fewer first), then by cell number; at most
    :data:`MAX_REACH_CELLS`, with their points."""
    step_x, step_y = ((region.size[:2] - 2.0 * margin) / (cols, rows)).tolist()
    lying = _objects_per_cell(world, region, rows, cols, margin)
    ranked = sorted(
        (((i % cols - index % cols) * step_x) ** 2 + ((i // cols - index // cols) * step_y) ** 2,
         lying.get(i, 0), i)
        for i in range(rows * cols)
        if i != index
    )
    chosen = [index] + [i for _, _, i in ranked[:MAX_REACH_CELLS - 1]]
    return [(i, grid_cell(region, i, rows, cols, margin, clearance)) for i in chosen]


def _objects_per_cell(world: Any, region: Region, rows: int, cols: int,
                      margin: float) -> dict[int, int]:
    """How many of the world's movable objects (the region's own body aside) have their
    centre in the region's box under each cell of the grid."""
    lo = region.lower[:2] + margin
    width = region.size[:2] - 2.0 * margin
    counts: dict[int, int] = {}
    for name, body in world.movable.items():
        if name == region.name:
            continue
        pos = pb.getBasePositionAndOrientation(body, physicsClientId=world.client)[0]
        if not region.contains(np.asarray(pos, dtype=float)):
            continue
        local = region.to_local(np.asarray(pos, dtype=float))
        col, row = ((local[:2] - lo) / width * (cols, rows)).tolist()
        if 0.0 <= col < cols and 0.0 <= row < rows:
            cell = int(row) * cols + int(col)
            counts[cell] = counts.get(cell, 0) + 1
    return counts
