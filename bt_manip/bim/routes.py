"""Routes from the stock to where each element is installed, through the building's doors.

:func:`floor_grid` paints the storey on a :class:`~bt_manip.bim.floor_grid.FloorGrid`: walls
between their passages, closed openings (their sills), and the obstacles, furniture and raised
walls within the robot's height band; each passage is labelled as a door.
:func:`check_routes` then asks, for each element, whether the robot carrying it crosswise (as
wide as the robot or the element, whichever is wider, plus :data:`CLEARANCE` each side) can go
from the stock's apron to within :data:`REACH_PLACE` of its place, and reports the doors that are
too narrow on the route the bare robot would take, or that no route exists at all.
"""

from __future__ import annotations

import math

from bt_manip.bim.building import PASSAGE_HEIGHT, Building
from bt_manip.bim.floor_grid import FloorGrid, Rect
from bt_manip.bim.ifc_input import IfcSource
from bt_manip.bim.schedule import InstallElement
from bt_manip.errors import Problem

CLEARANCE = 0.05
"""Free space (m) wanted on each side of the robot, or of what it carries, in a passage."""
REACH_STOCK = 1.0
"""The robot picks an element up from within this distance (m) of the stock pose."""
REACH_PLACE = 1.5
"""The robot installs an element from within this distance (m) of its target."""


def floor_grid(building: Building) -> FloorGrid:
    """The floor with the walls (between passages), closed openings and furniture painted."""
    grid = FloorGrid(building.extent)
    door_index = 0
    for wall in building.walls:
        yaw = math.atan2(wall.end[1] - wall.start[1], wall.end[0] - wall.start[0])
        cuts = [(o.start, o.end) for o in wall.openings if o.passage]
        s = 0.0
        for a, b in [*cuts, (wall.length, wall.length)]:
            if a - s > 1e-6:
                cx, cy = wall.point_at((s + a) / 2)
                grid.block(Rect(cx, cy, a - s, wall.thickness, yaw))
            s = max(s, b)
        for o in wall.openings:
            if o.passage:
                cx, cy = wall.point_at((o.start + o.end) / 2)
                grid.mark_door(Rect(cx, cy, o.width, wall.thickness + 0.1, yaw), door_index)
                door_index += 1
    band_top = building.band_top or PASSAGE_HEIGHT
    for f in building.raised + building.curtain_walls + building.obstacles + building.furniture:
        for box in f.boxes:
            if box.bottom < band_top:
                grid.block(Rect(box.centre[0], box.centre[1], box.size[0], box.size[1],
                                box.yaw))
    return grid


def doors_of(building: Building) -> list[tuple[str, float, tuple[float, float]]]:
    """(wall name, width, centre) of every passage, in the grid's door order."""
    out = []
    for wall in building.walls:
        for o in wall.openings:
            if o.passage:
                out.append((str(wall.entity.Name or wall.name), o.width,
                            wall.point_at((o.start + o.end) / 2)))
    return out


def check_routes(
    source: IfcSource, building: Building, grid: FloorGrid, elements: list[InstallElement],
    apron: tuple[float, float, float], robot_width: float,
) -> None:
    """Each element can be carried from the stock to its place (see :mod:`floor_grid`); the
    problems are collected in ``source``."""
    for element, message in route_problems(building, grid, elements, apron, robot_width):
        if element is None:
            source.problems.append(Problem("--stock", None, message))
        else:
            source.fail(source.model.by_id(element.step_id), message)


def route_problems(
    building: Building, grid: FloorGrid, elements: list[InstallElement],
    apron: tuple[float, float, float], robot_width: float,
) -> list[tuple[InstallElement | None, str]]:
    """The elements that cannot be carried to their places, each with its reason (None: the
    stock's apron itself has no room, and nothing is checked further)."""
    doors = doors_of(building)
    bare = robot_width / 2 + CLEARANCE
    a = (apron[0], apron[1])
    if not grid.joined(a, a, bare, REACH_STOCK):
        return [(None, "the robot has no room to stand at the stock's apron")]
    out: list[tuple[InstallElement | None, str]] = []
    for e in elements:
        need = max(robot_width, e.size[0]) + 2 * CLEARANCE
        b = (e.target["x"], e.target["y"])
        if grid.joined(a, b, need / 2, REACH_PLACE):
            continue
        if not grid.joined(a, b, bare, REACH_PLACE):
            out.append((e, f"its place ({b[0]:.2f}, {b[1]:.2f}) cannot be reached: no route for "
                           "the robot joins the stock to it"))
            continue
        route = grid.doors_on_route(a, b, bare, REACH_PLACE) or []
        narrow = [doors[i] for i in route if doors[i][1] < need]
        where = (
            "; its route from the stock passes "
            + ", ".join(f"the {w:.2f} m door of wall '{n}' at ({c[0]:.2f}, {c[1]:.2f})"
                        for n, w, c in narrow)
            if narrow
            else "; a passage on its route from the stock is narrower"
        )
        out.append((e, f"{e.size[0]:.2f} m long, it needs a passage {need:.2f} m wide when "
                       f"carried, wider than any door on its route{where}"))
    return out
