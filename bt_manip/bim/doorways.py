"""Doorways on the way from the stock to each place, and the poses to cross them straight.

A long element carried across the robot leaves little room in a doorway (a 1.2 m panel in a
1.6 m door: 20 cm each side), and a path follower that corrects its heading in the doorway
sweeps the element's ends into the jambs. So the installation tree crosses each door on an
element's route in two moves: a drive to the pose :data:`SIDE` metres before the door, facing
straight through it, then a straight drive (DriveStraight) to the pose :data:`BEYOND` metres
beyond it.

:func:`crossings` gives, per element, the doors its route from the stock crosses (the floor
grid's shortest route, as the converter's route check finds it) in order, each with the side
it is entered from; :func:`door_poses` gives the named poses of the world for them:
``door<i>_from_a`` and ``door<i>_to_b`` for a crossing from side ``a`` (the side the wall's
left normal points to) to side ``b``, and ``door<i>_from_b``, ``door<i>_to_a`` the other way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from bt_manip.bim.building import Building
from bt_manip.bim.floor_grid import FloorGrid
from bt_manip.bim.routes import CLEARANCE, REACH_PLACE
from bt_manip.bim.schedule import InstallElement
from bt_manip.bim.world_file import r

START_REACH = 0.5
"""Routes start within this distance (m) of the stock's apron pose."""
SIDE = 1.3
"""Distance (m) of the pose before a door from its centre line."""
BEYOND = 1.6
"""Distance (m) of the pose beyond a door from its centre line: room for the robot to turn
with its load there without sweeping it into the wall it has just passed."""


@dataclass(frozen=True)
class Door:
    """A passage: its index (the floor grid's door order), centre and the wall's left normal."""

    index: int
    x: float
    y: float
    nx: float
    ny: float

    def side_of(self, x: float, y: float) -> str:
        """``a`` when (x, y) lies on the normal's side, else ``b``."""
        return "a" if (x - self.x) * self.nx + (y - self.y) * self.ny >= 0 else "b"


@dataclass(frozen=True)
class Crossing:
    """A door crossed from side ``start`` to the other side."""

    door: int
    start: str

    @property
    def near(self) -> str:
        return f"door{self.door}_from_{self.start}"

    @property
    def far(self) -> str:
        return f"door{self.door}_to_{'b' if self.start == 'a' else 'a'}"


def doors_of(building: Building) -> list[Door]:
    """Every passage of the building, in the floor grid's door order."""
    out: list[Door] = []
    for wall in building.walls:
        length = wall.length
        ux = (wall.end[0] - wall.start[0]) / length
        uy = (wall.end[1] - wall.start[1]) / length
        for o in wall.openings:
            if o.passage:
                cx, cy = wall.point_at((o.start + o.end) / 2)
                out.append(Door(len(out), cx, cy, -uy, ux))
    return out


def crossings(
    building: Building, grid: FloorGrid, elements: list[InstallElement],
    apron: tuple[float, float, float], robot_width: float,
) -> dict[str, list[Crossing]]:
    """Per element (by world object), the doors on its route from the stock, in order."""
    doors = doors_of(building)
    out: dict[str, list[Crossing]] = {}
    for e in elements:
        need = max(robot_width, e.size[0]) + 2 * CLEARANCE
        b = (e.target["x"], e.target["y"])
        route = grid.doors_on_route(
            (apron[0], apron[1]), b, need / 2, REACH_PLACE, start_reach=START_REACH
        ) or []
        at = (apron[0], apron[1])
        found = []
        for i in route:
            door = doors[i]
            start = door.side_of(*at)
            found.append(Crossing(i, start))
            # the next door is entered from the side of this one it leads to
            at = (door.x - door.nx * BEYOND, door.y - door.ny * BEYOND) if start == "a" else (
                door.x + door.nx * BEYOND, door.y + door.ny * BEYOND)
        out[e.object] = found
    return out


def door_poses(used: set[int], building: Building) -> dict[str, list[float]]:
    """The named poses (x, y, yaw) of the crossings of the doors ``used``."""
    out: dict[str, list[float]] = {}
    for door in doors_of(building):
        if door.index not in used:
            continue
        into_b = math.atan2(-door.ny, -door.nx)
        into_a = math.atan2(door.ny, door.nx)
        for side, sign, facing in (("a", 1.0, into_b), ("b", -1.0, into_a)):
            near = (door.x + sign * door.nx * SIDE, door.y + sign * door.ny * SIDE)
            far = (door.x - sign * door.nx * BEYOND, door.y - sign * door.ny * BEYOND)
            other = "b" if side == "a" else "a"
            out[f"door{door.index}_from_{side}"] = [r(near[0]), r(near[1]), r(facing)]
            out[f"door{door.index}_to_{other}"] = [r(far[0]), r(far[1]), r(facing)]
    return out
