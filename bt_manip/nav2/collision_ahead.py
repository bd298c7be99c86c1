"""FollowPath's look ahead: is an object now lying on the stretch of path just in front of the
robot?

Nav2's controllers check the motion they are about to make against the local costmap and give
up (106 NO_VALID_CONTROL) when it would hit something. bt-manip's FollowPath does the same on
the robot's map: every :data:`CHECK_PERIOD` s of sim time (the local costmap's update rate) it
redraws the movable objects where they are now and looks at the next :data:`LOOKAHEAD` m of the
path; a movable object closer to that stretch than the robot's half width blocks it. Only
movable objects count: the path was planned clear of the walls and furniture, and an object
that was there when it was planned was planned round.

When the run localises, the robot knows of no movable object: the check reads its local
costmap instead (:mod:`bt_manip.navigation.rolling_window`), and a laser mark within the
robot's half width of the stretch blocks it (named "an obstacle in the local costmap").
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bt_manip.navigation.navigator import Navigator

LOOKAHEAD = 0.8
"""Metres of path in front of the robot that FollowPath checks: a second of driving at the path
follower's top speed (Nav2's Regulated Pure Pursuit looks a second ahead by default)."""
LOCAL_MARK = "an obstacle in the local costmap"
"""What a laser mark on the path ahead is called (costmap layers know no object's name)."""
CHECK_PERIOD = 0.2
"""Sim seconds between two checks (Nav2's local costmap is updated at 5 Hz by default)."""


@dataclass(frozen=True)
class Blocked:
    """A movable object on the path ahead: its name and how far along the path it is (m)."""

    name: str
    distance: float


def stretch_ahead(points: np.ndarray, position: tuple[float, float],
                  lookahead: float = LOOKAHEAD) -> tuple[np.ndarray, np.ndarray]:
    """The path points (of ``points``, (n, 2)) from the one nearest ``position`` on, up to
    ``lookahead`` metres along the path, and their distances along it from that point."""
    d = np.hypot(points[:, 0] - position[0], points[:, 1] - position[1])
    i = int(np.argmin(d))
    ahead = points[i:]
    steps = np.hypot(*np.diff(ahead, axis=0).T) if len(ahead) > 1 else np.zeros(0)
    s = np.concatenate([[0.0], np.cumsum(steps)])
    keep = s <= lookahead
    return ahead[keep], s[keep]


def blocked_ahead(nav: Navigator, points: np.ndarray, position: tuple[float, float],
                  ignore: frozenset[int] = frozenset(),
                  lookahead: float = LOOKAHEAD) -> Blocked | None:
    """The nearest movable object (not carried, not in ``ignore``) that lies within the robot's
    half width of the next ``lookahead`` m of the path ``points`` (the robot's turning point
    along it, from ``position``); None when the stretch is clear. Redraws the robot's map.
    With costmap layers, the nearest laser mark of the local costmap instead."""
    nav.refresh()
    grid = nav.costmap.grid
    if nav.layers is not None:
        ahead, s = stretch_ahead(points, position, lookahead)
        k = nav.layers.local.first_in_way(ahead, nav.footprint.half_width)
        return None if k is None else Blocked(LOCAL_MARK, float(s[k]))
    if not grid.sources:
        return None
    ahead, s = stretch_ahead(points, position, lookahead)
    reach = nav.footprint.half_width + grid.resolution / np.sqrt(2.0)
    cols = grid.shape[1]
    best: Blocked | None = None
    for body, cells in grid.sources.items():
        if body in ignore or body in nav.attached or cells.size == 0:
            continue
        cx = grid.origin[0] + (cells % cols + 0.5) * grid.resolution
        cy = grid.origin[1] + (cells // cols + 0.5) * grid.resolution
        near = np.hypot(ahead[:, 0, None] - cx[None, :], ahead[:, 1, None] - cy[None, :]).min(
            axis=1) <= reach
        if near.any():
            at = float(s[int(np.argmax(near))])
            if best is None or at < best.distance:
                best = Blocked(nav.movable.get(body, f"body {body}"), at)
    return best


@dataclass
class AheadWatch:
    """When FollowPath next looks ahead: at its first step, then every :data:`CHECK_PERIOD`."""

    period: float = CHECK_PERIOD
    last: float | None = field(default=None)

    def due(self, now: float) -> bool:
        """True (and the check counted as done now) when a check is due at sim time ``now``."""
        if self.last is not None and now - self.last < self.period - 1e-9:
            return False
        self.last = now
        return True
