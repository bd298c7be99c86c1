"""Where the 3D views put their camera: behind and above the robot, with no wall in between.

Both pages look at the first robot (the live page and the replay's "follow robot" keep it in
the middle as it moves) from a fixed offset. :func:`clear_offset` picks that offset among a few
candidates, in order of preference (behind the robot and to one side, not too steep, first;
then from other sides; then from higher up), by casting rays in the World from points on the
robot (low and high, at its centre and around its outline) to each candidate camera position,
at the robot's positions in the frames that matter. A candidate is penalised by how many rays
a wall or piece of furniture blocks, the first and last frames counting most. Casting rays only
reads the simulation.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from bt_manip.geometry import yaw_of
from bt_manip.sim import pybullet_queries as pbq
from bt_manip.viz.scene import ROOT

DISTANCE = 3.0
"""Camera distance (m) from the robot's ground point."""
ELEVATIONS_DEG = (38.0, 52.0, 66.0, 80.0)
AZIMUTHS_DEG = (-40.0, 40.0, 0.0, -80.0, 80.0, -120.0, 120.0, 180.0)
"""Directions around the robot, 0 = straight behind it (against its heading); behind and to
one side first, so that the robot does not hide what it works on."""
HEIGHT_FRACTIONS = (0.3, 0.95)
"""Where on the robot the rays start, as fractions of its height ..."""
SPREAD_FRACTIONS = ((0.0, 0.0), (1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0))
"""... and around its base (its centre and four points on its outline), so that no part of it
is hidden."""
LOOK_FRACTION = 0.45
"""The views look at this fraction of the robot's height above its base (its middle, not its
wheels)."""
END_WEIGHT = 10
"""How much more a blocked view of the first or last frame counts than one in between."""
MIDDLE_FRAMES = 24


@dataclass(frozen=True)
class CameraView:
    """A camera that looks at ``target`` from ``target + offset`` (world frame, metres);
    ``target`` is at the robot's look height (:data:`LOOK_FRACTION`)."""

    target: tuple[float, float, float]
    offset: tuple[float, float, float]
    follow: str = ""
    """Scene path of the body the view follows ('' when none)."""

    def to_json(self) -> dict[str, Any]:
        return {
            "target": [round(v, 4) for v in self.target],
            "offset": [round(v, 4) for v in self.offset],
            "follow": self.follow,
        }


DEFAULT_OFFSET = (-2.4, -2.0, 1.9)


def candidate_offsets(yaw: float) -> list[tuple[float, float, float]]:
    """Camera offsets in order of preference for a robot heading ``yaw`` (rad)."""
    out = []
    for elevation in ELEVATIONS_DEG:
        el = math.radians(elevation)
        for azimuth in AZIMUTHS_DEG:
            a = yaw + math.pi + math.radians(azimuth)
            horizontal = DISTANCE * math.cos(el)
            out.append(
                (horizontal * math.cos(a), horizontal * math.sin(a), DISTANCE * math.sin(el))
            )
    return out


def _blocked(world: Any, starts: np.ndarray, ends: np.ndarray, blockers: set[int]) -> np.ndarray:
    """Which of the segments start -> end cross a blocker (other bodies are seen through)."""
    c = world.client
    out = np.zeros(len(starts), dtype=bool)
    todo = list(range(len(starts)))
    origin = starts.copy()
    for _ in range(4):  # look past up to three bodies that are not blockers
        if not todo:
            break
        hits = pbq.ray_hits(c, origin[todo].tolist(), ends[todo].tolist())
        again = []
        for k, hit in zip(todo, hits, strict=True):
            body = hit.body
            if body < 0:
                continue
            if body in blockers:
                out[k] = True
                continue
            direction = ends[k] - starts[k]
            origin[k] = np.asarray(hit.position) + 1e-3 * direction / np.linalg.norm(direction)
            again.append(k)
        todo = again
    return out


def _extent(client: int, body: int) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned box around every link of a body."""
    boxes = [
        pbq.aabb(client, body, link) for link in range(-1, pbq.joint_count(client, body))
    ]
    return np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0)


def look_height(world: Any, robot_body: int) -> float:
    """Height (m) above the floor that the views look at: the middle of the robot."""
    lo, hi = _extent(world.client, robot_body)
    return cast(float, LOOK_FRACTION * max(0.2, hi[2] - max(0.0, lo[2])))


def _ray_ends(world: Any, robot_body: int, positions: Sequence[np.ndarray],
              offset: Sequence[float], per_position: int) -> np.ndarray:
    """The camera position for each ray: the look point above each position, plus offset."""
    look = look_height(world, robot_body)
    centres = np.repeat(np.array([[p[0], p[1]] for p in positions]), per_position, axis=0)
    return np.column_stack(
        [centres + np.asarray(offset[:2]), np.full(len(centres), look + offset[2])]
    )


def _ray_starts(
    world: Any, robot_body: int, positions: Sequence[np.ndarray]
) -> np.ndarray:
    """Points on the robot (see :data:`HEIGHT_FRACTIONS`, :data:`SPREAD_FRACTIONS`) at each
    of ``positions``: rows x, y, z, one block of rows per position."""
    lo, hi = _extent(world.client, robot_body)
    height = max(0.2, hi[2] - max(0.0, lo[2]))
    radius = 0.5 * max(hi[0] - lo[0], hi[1] - lo[1]) / math.sqrt(2.0)
    return np.array(
        [[p[0] + sx * radius, p[1] + sy * radius, f * height]
         for p in positions for sx, sy in SPREAD_FRACTIONS for f in HEIGHT_FRACTIONS],
        dtype=float,
    )


def hidden_rays(
    world: Any, robot_body: int, positions: Sequence[np.ndarray], offset: Sequence[float]
) -> int:
    """How many rays from points on the robot at ``positions`` to the camera at ``offset``
    from it a wall or piece of furniture blocks (0: the robot is in full view)."""
    starts = _ray_starts(world, robot_body, positions)
    per_position = len(HEIGHT_FRACTIONS) * len(SPREAD_FRACTIONS)
    ends = _ray_ends(world, robot_body, positions, offset, per_position)
    return int(_blocked(world, starts, ends, set(world.obstacle_body_ids())).sum())


def clear_offset(
    world: Any, robot_body: int, positions: Sequence[np.ndarray], yaw: float,
    weights: Sequence[int] | None = None,
) -> tuple[float, float, float]:
    """The most preferred offset from which the robot at ``positions`` (its base, world x, y)
    is least hidden by walls and furniture (see the module docstring)."""
    blockers = set(world.obstacle_body_ids())
    weights = list(weights) if weights is not None else [1] * len(positions)
    starts = _ray_starts(world, robot_body, positions)
    per_position = len(HEIGHT_FRACTIONS) * len(SPREAD_FRACTIONS)
    w = np.repeat(weights, per_position)
    best, best_score = DEFAULT_OFFSET, math.inf
    for rank, offset in enumerate(candidate_offsets(yaw)):
        ends = _ray_ends(world, robot_body, positions, offset, per_position)
        score = float(w[_blocked(world, starts, ends, blockers)].sum()) * 1000 + rank
        if score < best_score:
            best, best_score = offset, score
        if score < 1000:  # nothing blocked: the most preferred clear view
            break
    return best


def _first_robot(world: Any) -> tuple[str, Any] | None:
    robots = getattr(world, "robots", None) or {}
    if not robots:
        return None
    name = next(iter(robots))
    return name, robots[name]


def live_camera(world: Any) -> CameraView:
    """The live page's view: the first robot where it stands now, from a clear offset."""
    first = _first_robot(world) if world is not None else None
    if first is None:
        return CameraView((0.0, 0.0, 0.0), DEFAULT_OFFSET)
    name, robot = first
    x, y, yaw = robot.base_pose2d()
    offset = clear_offset(world, robot.body, [np.array([x, y])], yaw)
    look = look_height(world, robot.body)
    return CameraView((float(x), float(y), look), offset, f"{ROOT}/{name}")


def replay_camera(world: Any, rec: Any) -> dict[str, Any]:
    """The replay's view: the first robot, from an offset clear at its first and last frames
    (and as clear as can be in between)."""
    first = _first_robot(world)
    if first is None or not rec.times:
        return CameraView((0.0, 0.0, 0.0), DEFAULT_OFFSET).to_json()
    name, robot = first
    path = f"{ROOT}/{name}"
    try:
        _, samples = rec.track_samples(path)
    except KeyError:
        return CameraView((0.0, 0.0, 0.0), DEFAULT_OFFSET).to_json()
    n = len(samples)
    picks = sorted({0, n - 1, *np.linspace(0, n - 1, MIDDLE_FRAMES).round().astype(int)})
    weights = [END_WEIGHT if k in (0, n - 1) else 1 for k in picks]
    q = samples[0][3:7]
    yaw = yaw_of(q)
    offset = clear_offset(world, robot.body, [samples[k][:2] for k in picks], yaw, weights)
    target = (float(samples[0][0]), float(samples[0][1]), look_height(world, robot.body))
    return CameraView(target, offset, path).to_json()
