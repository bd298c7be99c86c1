"""What the filter reads: odometry poses and planar laser scans, as small frozen records.

The fields are plain so that a sensor's own records map onto them one for one:

- :class:`OdomPose`: the base's pose ``(x, y, yaw)`` in the odometry frame. Only differences
  between two odometry poses matter; the filter keeps the map -> odom relation itself.
- :class:`Scan`: ``ranges`` (m, one per beam, counter-clockwise from ``angle_min`` in steps of
  ``angle_increment``), ``range_max`` (a reading at or beyond it, or not finite, is "no return"
  and is ignored), and ``sensor_pose``, the scanner's ``(x, y, yaw)`` in the base frame.

Both check their numbers when made and raise ``ValueError`` naming the field at fault.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

MAX_SCAN_BEAMS = 100_000
"""Most readings one scan may hold."""


@dataclass(frozen=True)
class OdomPose:
    """The base's pose in the odometry frame at ``time`` (s)."""

    x: float
    y: float
    yaw: float
    time: float = 0.0

    def __post_init__(self) -> None:
        for name in ("x", "y", "yaw", "time"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"odometry pose: {name} must be a finite number, not {v!r}")


@dataclass(frozen=True)
class Scan:
    """One planar laser scan."""

    ranges: np.ndarray
    angle_min: float
    angle_increment: float
    range_max: float
    sensor_pose: tuple[float, float, float] = (0.0, 0.0, 0.0)
    time: float = 0.0
    angles: np.ndarray = field(init=False, repr=False, compare=False)
    """Each beam's angle in the sensor frame (rad), worked out once."""

    def __post_init__(self) -> None:
        r = np.asarray(self.ranges, dtype=float)
        if r.ndim != 1 or r.size == 0:
            raise ValueError(f"scan: ranges must be a non-empty 1-D array, not shape {r.shape}")
        if r.size > MAX_SCAN_BEAMS:
            raise ValueError(f"scan: {r.size:,} ranges, more than the {MAX_SCAN_BEAMS:,} allowed")
        for name in ("angle_min", "angle_increment", "range_max", "time"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"scan: {name} must be a finite number, not {v!r}")
        if self.range_max <= 0:
            raise ValueError(f"scan: range_max must be > 0, not {self.range_max}")
        if self.angle_increment == 0 and r.size > 1:
            raise ValueError("scan: angle_increment must not be 0 when there are several beams")
        pose = tuple(self.sensor_pose)
        if len(pose) != 3 or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in pose
        ):
            raise ValueError(f"scan: sensor_pose must be three finite numbers (x, y, yaw), "
                             f"not {self.sensor_pose!r}")
        r.flags.writeable = False
        object.__setattr__(self, "ranges", r)
        object.__setattr__(self, "sensor_pose", tuple(float(v) for v in pose))
        angles = self.angle_min + self.angle_increment * np.arange(r.size)
        angles.flags.writeable = False
        object.__setattr__(self, "angles", angles)
