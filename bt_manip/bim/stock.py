"""The stock area: where the elements to install wait, each standing in a slotted stand.

The stands stand one behind the other along the stock's heading (``yaw``), :func:`spacing`
apart, each element upright in its slot with its length across the heading, the first to
install nearest the apron. The robot reaches them from the apron, a free strip :data:`APRON`
long before the stock's back end (the ``stock`` pose of the world, facing the stands): it faces
the first element square on, and each next one from where the ones taken stood. The rails are
lower (:data:`RAIL`) than the lowest obstacle the navigator maps (2 cm), so the robot drives
over an empty stand. The whole stock (stands, elements and the ``stock`` pose) moves rigidly
by up to :data:`SHIFT` m and :data:`TURN` rad per seed (a world ``groups:`` entry).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from bt_manip.bim.floor_grid import FloorGrid, Rect
from bt_manip.bim.world_file import pose3, r

APRON = 1.8
"""Free floor (m) kept before the stands for the robot."""
SLOT_GAP = 0.01
"""Play (m) between an element and each rail of its slot."""
RAIL = (0.02, 0.006)
"""Width and height (m) of a stand's rails."""
SHIFT = 0.08
"""Largest shift (m in x and y) of the whole stock (stands and elements together), per seed."""
TURN = 0.05
"""Largest turn (rad) of the whole stock, per seed."""
MARGIN = 0.35
"""Free floor (m) kept around the stands and the apron when the stock is placed."""


@dataclass(frozen=True)
class StockPose:
    """Centre of the stands and the heading of the elements in them."""

    x: float
    y: float
    yaw: float


@dataclass(frozen=True)
class Slot:
    """Where one element stands: its centre on the floor and heading."""

    x: float
    y: float
    yaw: float


def spacing(thicknesses: list[float]) -> float:
    """Distance (m) between neighbouring slots: room for the gripper between elements."""
    return max(0.45, max(thicknesses, default=0.0) + 0.4)


def stock_size(sizes: list[tuple[float, float, float]]) -> tuple[float, float]:
    """Length (along the heading) and width of the stands' area."""
    width = max((s[0] for s in sizes), default=0.5) + 0.2
    length = (len(sizes) - 1) * spacing([s[1] for s in sizes]) + max(
        (s[1] for s in sizes), default=0.0
    ) + 2 * (SLOT_GAP + RAIL[0]) + 0.1
    return length, width


def footprint(pose: StockPose, sizes: list[tuple[float, float, float]]) -> Rect:
    """The stands' area and the apron together."""
    length, width = stock_size(sizes)
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    return Rect(pose.x - c * APRON / 2, pose.y - s * APRON / 2, length + APRON, width, pose.yaw)


def apron_pose(
    pose: StockPose, sizes: list[tuple[float, float, float]]
) -> tuple[float, float, float]:
    """The robot's pose on the apron, facing the stands."""
    length, _ = stock_size(sizes)
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    d = length / 2 + APRON / 2
    return (pose.x - c * d, pose.y - s * d, pose.yaw)


def slots(pose: StockPose, sizes: list[tuple[float, float, float]]) -> list[Slot]:
    """One slot per element, in installation order, from the apron's side; each element's
    length lies across the heading."""
    step = spacing([s[1] for s in sizes])
    n = len(sizes)
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    across = math.atan2(math.sin(pose.yaw + math.pi / 2), math.cos(pose.yaw + math.pi / 2))
    out = []
    for k in range(n):
        u = (k - (n - 1) / 2) * step
        out.append(Slot(pose.x + c * u, pose.y + s * u, across))
    return out


def stock_poses(
    grid: FloorGrid, area: Rect, sizes: list[tuple[float, float, float]], limit: int = 50
) -> list[StockPose]:
    """Stock poses inside ``area`` (a space) whose stands and apron, with :data:`MARGIN` beside
    them and beyond the stands, are free; farthest from the area's centre (which stays free for
    the robot) first, at most ``limit``. Headings along the area's axes are tried, on a 0.25 m
    grid of centres."""
    length, width = stock_size(sizes)
    found: list[tuple[float, int, StockPose]] = []
    step = 0.25
    nu = int(area.length / step) + 1
    nv = int(area.width / step) + 1
    ac, as_ = math.cos(area.yaw), math.sin(area.yaw)
    centres = []
    for i in range(nu):
        for j in range(nv):
            du = -area.length / 2 + i * step
            dv = -area.width / 2 + j * step
            centres.append((du * du + dv * dv, area.x + ac * du - as_ * dv,
                            area.y + as_ * du + ac * dv))
    centres.sort(reverse=True)
    for k, turn in enumerate((0.0, math.pi / 2, math.pi, -math.pi / 2)):
        yaw = area.yaw + turn
        c, s = math.cos(yaw), math.sin(yaw)
        for dist2, fx, fy in centres:
            # (fx, fy) is the centre of the stands and apron together
            rect = Rect(fx, fy, length + APRON, width, yaw)
            # the margin on both sides and beyond the stands; the apron may end at a wall
            kept = Rect(fx + c * MARGIN / 2, fy + s * MARGIN / 2, length + APRON + MARGIN,
                        width + 2 * MARGIN, yaw)
            if not _within(area, rect) or not grid.is_free(kept):
                continue
            pose = StockPose(fx + c * APRON / 2, fy + s * APRON / 2, math.atan2(s, c))
            found.append((-dist2, k, pose))
    found.sort(key=lambda f: (f[0], f[1]))
    return [f[2] for f in found[:limit]]


def place_stock(
    grid: FloorGrid, area: Rect, sizes: list[tuple[float, float, float]]
) -> StockPose | None:
    """The first of :func:`stock_poses`, or None."""
    poses = stock_poses(grid, area, sizes, limit=1)
    return poses[0] if poses else None


def _within(area: Rect, rect: Rect) -> bool:
    c, s = math.cos(area.yaw), math.sin(area.yaw)
    rc, rs = math.cos(rect.yaw), math.sin(rect.yaw)
    for su in (-1, 1):
        for sv in (-1, 1):
            px = rect.x + rc * su * rect.length / 2 - rs * sv * rect.width / 2 - area.x
            py = rect.y + rs * su * rect.length / 2 + rc * sv * rect.width / 2 - area.y
            if abs(px * c + py * s) > area.length / 2 + 1e-6:
                return False
            if abs(-px * s + py * c) > area.width / 2 + 1e-6:
                return False
    return True


def stand_entry(name: str, slot: Slot, size: tuple[float, float, float]) -> dict[str, Any]:
    """A stand: two rails along the element, leaving a slot :data:`SLOT_GAP` wider each side."""
    rail_len = max(size[0] - 0.1, 0.1)
    off = size[1] / 2 + SLOT_GAP + RAIL[0] / 2
    return {
        "name": name,
        "colour": "dark_grey",
        "pose": pose3(slot.x, slot.y, 0.0, slot.yaw),
        "parts": [
            {"shape": "box", "size": [r(rail_len), RAIL[0], RAIL[1]],
             "xyz": [0.0, r(side * off), RAIL[1] / 2]}
            for side in (1, -1)
        ],
    }


def stand_rects(slot: Slot, size: tuple[float, float, float]) -> list[Rect]:
    """The floor taken by a stand and its element."""
    off = size[1] / 2 + SLOT_GAP + RAIL[0] / 2
    c, s = math.cos(slot.yaw), math.sin(slot.yaw)
    return [
        Rect(slot.x, slot.y, size[0], size[1] + 2 * (SLOT_GAP + RAIL[0]), slot.yaw),
        *(Rect(slot.x - s * side * off, slot.y + c * side * off, max(size[0] - 0.1, 0.1),
               RAIL[0], slot.yaw) for side in (1, -1)),
    ]


def element_entry(
    name: str, slot: Slot, size: tuple[float, float, float], mass: float
) -> dict[str, Any]:
    """The element as a movable box standing in its slot, jittered per seed."""
    return {
        "name": name,
        "shape": "box",
        "size": [r(s) for s in size],
        "mass": r(mass),
        "friction": 0.9,
        "colour": "white",
        "pose": pose3(slot.x, slot.y, size[2] / 2 + 0.0005, slot.yaw),
    }


def stock_group(pose: StockPose, members: list[str]) -> dict[str, Any]:
    """The world's ``groups:`` entry that moves the stands, the elements and the ``stock`` pose
    together, by up to :data:`SHIFT` and :data:`TURN` per seed."""
    return {
        "name": "stock_area",
        "members": members,
        "origin": [r(pose.x), r(pose.y)],
        "randomize": {"x": [-SHIFT, SHIFT], "y": [-SHIFT, SHIFT], "yaw": [-TURN, TURN]},
    }
