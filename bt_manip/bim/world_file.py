"""The world YAML of a building: walls with their openings, boxes, stands, objects, robot.

The document follows ``worlds/README.md``: walls with ``doors`` cut where the building has
openings (a window's cut is closed below and above by a sill and a lintel, static boxes named
``<wall>_sill_<i>`` and ``<wall>_lintel_<i>``), furniture as boxes, the elements to install as
movable boxes standing in slotted stands at the stock, the robot and named poses. An obstacle
that is no box (a round column, a curved desk) is one entry of ``parts``: the strips of its
footprint, turned with it.
"""

from __future__ import annotations

import math
from typing import Any

from bt_manip.bim.building import Building, Furniture, Wall
from bt_manip.bim.shapes import Box

DIGITS = 4
"""Decimals written (0.1 mm, 0.0001 rad)."""


def r(value: float) -> float:
    return round(float(value), DIGITS) + 0.0  # + 0.0: no "-0.0" in the file


def pose3(x: float, y: float, z: float, yaw: float) -> dict[str, list[float]]:
    return {"xyz": [r(x), r(y), r(z)], "rpy": [0.0, 0.0, r(yaw)]}


def box_entry(name: str, box: Box, colour: str) -> dict[str, Any]:
    """A static box (furniture) around ``box``."""
    return {
        "name": name,
        "shape": "box",
        "size": [r(max(s, 0.001)) for s in box.size],
        "pose": pose3(*box.centre, box.yaw),
        "colour": colour,
    }


def obstacle_entry(item: Furniture, colour: str) -> dict[str, Any]:
    """A static obstacle: one box, or the boxes of its footprint as parts."""
    if not item.parts:
        return box_entry(item.name, item.box, colour)
    c, s = item.box.axis()
    cx, cy, cz = item.box.centre
    parts = []
    for b in item.parts:
        dx, dy = b.centre[0] - cx, b.centre[1] - cy
        parts.append({
            "shape": "box",
            "size": [r(max(v, 0.001)) for v in b.size],
            "xyz": [r(c * dx + s * dy), r(-s * dx + c * dy), r(b.centre[2] - cz)],
        })
    return {"name": item.name, "parts": parts, "pose": pose3(cx, cy, cz, item.box.yaw),
            "colour": colour}


def wall_entries(wall: Wall) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The wall's entry (doors at every opening) and the sills and lintels of its openings
    that are no passage."""
    entry: dict[str, Any] = {
        "name": wall.name,
        "from": [r(wall.start[0]), r(wall.start[1])],
        "to": [r(wall.end[0]), r(wall.end[1])],
        "thickness": r(wall.thickness),
        "height": r(wall.top),
        "colour": "beige",
    }
    length = float(f"{math.dist(entry['from'], entry['to']):.6f}")
    doors = []
    boxes: list[dict[str, Any]] = []
    yaw = math.atan2(wall.end[1] - wall.start[1], wall.end[0] - wall.start[0])
    for i, o in enumerate(wall.openings):
        start = max(o.start, 0.0)
        end = min(o.end, length)
        at, width = r((start + end) / 2), r(end - start)
        if at - width / 2 < 0 or at + width / 2 > length:  # rounded past an end of the wall
            width = r(width - 2 * 10**-DIGITS)
        if width <= 0:
            continue
        doors.append({"at": at, "width": width})
        if o.passage:
            continue
        cx, cy = wall.point_at((start + end) / 2)
        if o.bottom > 0.005:
            boxes.append(
                box_entry(f"{wall.name}_sill_{i}",
                          Box((cx, cy, o.bottom / 2), (width, wall.thickness, o.bottom), yaw),
                          "beige")
            )
        if wall.top - o.top > 0.005:
            h = wall.top - o.top
            boxes.append(
                box_entry(f"{wall.name}_lintel_{i}",
                          Box((cx, cy, o.top + h / 2), (width, wall.thickness, h), yaw), "beige")
            )
    if doors:
        entry["doors"] = doors
    return entry, boxes


def building_entries(building: Building) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """The ``walls`` and ``furniture`` lists of the building."""
    walls: list[dict[str, Any]] = []
    furniture: list[dict[str, Any]] = []
    for wall in building.walls:
        entry, boxes = wall_entries(wall)
        walls.append(entry)
        furniture += boxes
    furniture += [obstacle_entry(f, "beige") for f in building.raised]
    furniture += [obstacle_entry(f, "cyan") for f in building.curtain_walls]
    furniture += [obstacle_entry(f, "grey") for f in building.obstacles]
    furniture += [obstacle_entry(f, "wood") for f in building.furniture]
    return walls, furniture
