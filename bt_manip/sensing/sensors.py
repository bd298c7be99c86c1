"""The ``sensors:`` section of a robot descriptor.

Each entry declares one sensor mounted on a link of the robot. The one kind so far is a
planar laser scanner (``type: lidar2d``)::

    sensors:
      - type: lidar2d
        name: front_laser        # unique among the robot's sensors
        link: top_plate_link     # the URDF link it is mounted on
        xyz: [0.45, 0.0, 0.105]  # its origin in that link's frame (m)
        rpy: [0.0, 0.0, 0.0]     # roll and pitch 0 (a level scanner); yaw turns the scan
        fov_deg: 270.0           # field of view, centred on the sensor's x axis
        beams: 541               # beams across the field of view
        range_m: 12.0            # farthest return (m)
        noise_m: 0.01            # standard deviation of each range (m)
        rate_hz: 10.0            # scans per second

Only ``type``, ``name`` and ``link`` are required; the other keys default to the values above
(:data:`LIDAR_DEFAULTS`). The records here are plain data: the scanner itself is
:class:`bt_manip.sensing.lidar.Lidar`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from bt_manip.sim.yaml_lines import FieldReader, LineDict

__all__ = ["LIDAR_DEFAULTS", "SENSOR_TYPES", "LidarSpec", "read_sensors"]

SENSOR_TYPES = ("lidar2d",)
LIDAR_KEYS = {"type", "name", "link", "xyz", "rpy", "fov_deg", "beams", "range_m", "noise_m",
              "rate_hz"}
LIDAR_DEFAULTS: dict[str, float] = {
    "fov_deg": 270.0,
    "beams": 541,
    "range_m": 12.0,
    "noise_m": 0.01,
    "rate_hz": 10.0,
}
"""A 270 degree scanner with half-degree steps and a 12 m reach, about 1 cm of range noise,
10 scans per second: the class of laser a Husky carries (SICK LMS1xx, Hokuyo UTM/UST)."""
MAX_BEAMS = 10_000
MAX_RANGE_M = 100.0
MAX_RATE_HZ = 100.0
MAX_SENSORS = 8
MAX_OFFSET = 10.0
"""Largest value (m, or rad) of a sensor's ``xyz`` or ``rpy``."""
LEVEL_TOLERANCE = math.radians(1.0)
"""Largest roll or pitch (rad) of a mounted 2D scanner: its scan plane is taken as level."""


@dataclass(frozen=True)
class LidarSpec:
    """A planar laser scanner declared in a robot descriptor (``type: lidar2d``)."""

    name: str
    link: str
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    fov_deg: float = LIDAR_DEFAULTS["fov_deg"]
    beams: int = int(LIDAR_DEFAULTS["beams"])
    range_m: float = LIDAR_DEFAULTS["range_m"]
    noise_m: float = LIDAR_DEFAULTS["noise_m"]
    rate_hz: float = LIDAR_DEFAULTS["rate_hz"]
    line: int = field(default=0, compare=False)
    """Line of the entry in its descriptor (0 when not read from a file)."""

    @property
    def angle_min(self) -> float:
        """Angle of the first beam (rad, counter-clockwise from the sensor's x axis)."""
        return -math.radians(self.fov_deg) / 2.0

    @property
    def angle_increment(self) -> float:
        """Angle between neighbouring beams (rad). A full circle is split into ``beams`` equal
        steps (the last beam is not the first again); a narrower field has beams at both
        ends."""
        fov = math.radians(self.fov_deg)
        if self.fov_deg >= 360.0 or self.beams == 1:
            return fov / self.beams
        return fov / (self.beams - 1)


def read_sensors(f: FieldReader, data: LineDict) -> tuple[LidarSpec, ...]:
    """The checked ``sensors`` list of a descriptor (absent: none); each problem is recorded
    in ``f`` with its line."""
    items = f.seq(data.get("sensors"), data.line_of("sensors"), "sensors")
    if items is not None and len(items) > MAX_SENSORS:
        f.fail(items.line, f"sensors: at most {MAX_SENSORS} sensors, got {len(items)}")
        return ()
    out: list[LidarSpec] = []
    names: set[str] = set()
    for _, here, d in f.entries(items, "sensors", LIDAR_KEYS):
        kind = d.get("type")
        if kind not in SENSOR_TYPES:
            f.fail(d.line_of("type"),
                   f"{here}.type must be one of {', '.join(SENSOR_TYPES)}, got {kind!r}")
            continue
        spec = _lidar(f, d, here)
        if spec is None:
            continue
        if spec.name in names:
            f.fail(d.line_of("name"), f"{here}.name: a second sensor named '{spec.name}'")
        names.add(spec.name)
        out.append(spec)
    return tuple(out)


def _lidar(f: FieldReader, d: LineDict, here: str) -> LidarSpec | None:
    before = len(f.problems)
    name = f.text(d, "name", here)
    link = f.text(d, "link", here)
    xyz = _triple(f, d, "xyz", here)
    rpy = _triple(f, d, "rpy", here)
    if abs(rpy[0]) > LEVEL_TOLERANCE or abs(rpy[1]) > LEVEL_TOLERANCE:
        f.fail(d.line_of("rpy"), f"{here}.rpy: a 2D laser scans a level plane; its roll and "
               "pitch must be 0 (within 1 degree)")
    fov = f.number(d, "fov_deg", here, LIDAR_DEFAULTS["fov_deg"], within=(1.0, 360.0))
    beams = f.number(d, "beams", here, LIDAR_DEFAULTS["beams"], within=(1, MAX_BEAMS))
    if beams is not None and beams != int(beams):
        f.fail(d.line_of("beams"), f"{here}.beams must be a whole number, got {d['beams']}")
    reach = f.number(d, "range_m", here, LIDAR_DEFAULTS["range_m"], within=(0.01, MAX_RANGE_M))
    noise = f.number(d, "noise_m", here, LIDAR_DEFAULTS["noise_m"], within=(0.0, 1.0))
    rate = f.number(d, "rate_hz", here, LIDAR_DEFAULTS["rate_hz"], within=(0.1, MAX_RATE_HZ))
    if len(f.problems) > before:
        return None
    assert fov is not None and beams is not None and reach is not None
    assert noise is not None and rate is not None
    return LidarSpec(name, link, xyz, rpy, fov, int(beams), reach, noise, rate, line=d.line)


def _triple(f: FieldReader, d: LineDict, key: str, here: str) -> tuple[float, float, float]:
    if key not in d:
        return (0.0, 0.0, 0.0)
    v = f.vector(d[key], 3, d.line_of(key), f"{here}.{key}")
    if v is None:
        return (0.0, 0.0, 0.0)
    if any(abs(x) > MAX_OFFSET for x in v):
        f.fail(d.line_of(key), f"{here}.{key}: each value within -{MAX_OFFSET:g}..{MAX_OFFSET:g}")
        return (0.0, 0.0, 0.0)
    return (v[0], v[1], v[2])
