"""Localisation in a run: per robot with a laser, a :class:`Localizer`; for the run, a
:class:`RunLocalization` stepped by the run loop before every tick.

A :class:`Localizer` holds one robot's :class:`~bt_manip.sensing.lidar.Lidar`,
:class:`~bt_manip.sensing.odometry.WheelOdometry` and
:class:`~bt_manip.localization.filter.ParticleFilter`. At each :meth:`Localizer.step` (once per
tick, before the tree is ticked):

- the odometry integrates what the wheels did since the last step;
- when a scan is due (every ``1 / rate_hz`` of sim time) the laser scans and the filter is
  given the scan with the odometry; it takes it only after its own travel thresholds
  (``update_min_d``, ``update_min_a``), as Nav2's AMCL does;
- when the filter took a scan, ``map -> odom`` is set from its estimate, so that the pose the
  robot believes it has between two filter updates is ``map -> odom`` composed with the
  current odometry (what AMCL publishes through tf);
- the error of that belief against the true base pose is sampled (:class:`ErrorLog`);
- when the robot's costmaps are due (:class:`~bt_manip.navigation.layered.RobotCostmaps`: the
  global one at 1 Hz, the local one at 5 Hz), they are given the latest scan (the filter's, or
  one cast for them, whose noise is drawn from a generator of their own so that the filter's
  draws stay as they were), laid in the map frame from the believed pose. While the base stands
  still (its odometry moved less than :data:`STILL_M` and :data:`STILL_RAD`), a scan is cast
  for them at most every :data:`STILL_RESCAN_S` (a deliberate saving: casting a scan is the
  dearest part of an update, and a still robot sees the same world unless something moves in
  it, which it then notices within that time). The self filter's returns (the robot itself and
  what it holds, :meth:`Localizer._own_returns`) are left out: the robot never marks itself or
  its load.

Every random draw comes from generators seeded by the episode seed and the robot's name
(:func:`bt_manip.sim.randomize.entity_rng`): the same seed gives the same run. Nothing here is
made when localisation is off, so a run without it draws nothing and writes nothing new.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from bt_manip.errors import InputError, Problem
from bt_manip.localization.estimate import PoseEstimate
from bt_manip.localization.filter import ParticleFilter
from bt_manip.localization.frames import Pose, compose, inverse, wrap
from bt_manip.localization.inputs import OdomPose
from bt_manip.localization.inputs import Scan as FilterScan
from bt_manip.localization.kidnap import kidnap
from bt_manip.localization.map_from_world import map_from_world, static_outlines
from bt_manip.localization.options import LocalizationOptions
from bt_manip.localization.surface import surface_field
from bt_manip.navigation.grid import DEFAULT_RESOLUTION, GridTooLarge, OccupancyGrid, bodies_extent
from bt_manip.navigation.layered import RobotCostmaps
from bt_manip.overlay import Overlay
from bt_manip.run.faults import (
    KIDNAP,
    LIDAR_DROPOUT,
    LIDAR_NOISE,
    ODOM_NOISE,
    FaultEvent,
    FaultInjector,
    localization_faults,
)
from bt_manip.sensing.lidar import Lidar, Scan
from bt_manip.sensing.odometry import Odometry, OdometryNoise, WheelOdometry
from bt_manip.sim.randomize import entity_rng
from bt_manip.sim.world_spec import LocalizationSpec

if TYPE_CHECKING:
    from bt_manip.sim.robot import Robot
    from bt_manip.sim.world import World

__all__ = [
    "DEFAULT_ODOMETRY_NOISE",
    "ERROR_THRESHOLD_M",
    "MIN_RETURN_M",
    "ErrorLog",
    "KidnapAt",
    "Localizer",
    "RunLocalization",
    "SensorFaults",
    "has_laser",
    "localization_for_run",
]

DEFAULT_ODOMETRY_NOISE = OdometryNoise(k=0.01, k_rot=0.02, k_drift=0.01)
"""How much a run's wheel odometry errs unless an ``odom_noise`` fault says otherwise: 1 cm of
travel error after 1 m, 0.02 rad of heading error per radian turned, 0.01 rad per metre."""
MIN_RETURN_M = 0.4
"""Returns nearer than this to the laser are left out of what the filter reads (the robot's
own wheels and bumpers, as a ROS laser filter would leave them out)."""
SELF_FILTER_PADDING = 0.05
"""A return within this (m) of where the robot's own model (its load included) would stop
the beam is taken as the robot itself and left out."""
MAP_RESOLUTION = 0.05
"""Cell side (m) of the localisation map."""
SCAN_HALF_BAND = 0.03
"""The map is cut this far (m) above and below the laser's scan plane."""
PARTICLES_DRAWN = 400
"""Most particles drawn on the overlay (every k-th of the set)."""
SCAN_COLOUR = (0.9, 0.1, 0.1, 1.0)
PARTICLE_COLOUR = (0.2, 0.35, 0.95, 1.0)
ERROR_THRESHOLD_M = 0.2
"""The report counts the sim seconds the position error spends above this (m)."""
MARKS_DRAWN = 1500
"""Most marks of the global costmap's obstacle layer drawn on the overlay (every k-th)."""
MARK_COLOUR = (1.0, 0.55, 0.0, 1.0)
STILL_M = 0.01
STILL_RAD = 0.01
"""Odometry travel (m) and turn (rad) below which the base counts as standing still."""
STILL_RESCAN_S = 1.0
"""Sim seconds between the costmaps' own scans while the base stands still."""
STATIC_MAP_PAD_M = 0.5
"""The costmaps cover the static obstacles' extent padded by this (m): the navigator's
static grid (:func:`~bt_manip.navigation.grid.rasterise`'s default pad)."""


def static_frame(world: World) -> OccupancyGrid | None:
    """An empty grid in the frame of the navigators' static grid (None when the world is too
    large to map: navigation then fails with the reason)."""
    obstacles = world.obstacle_body_ids()
    if not obstacles:
        return None
    try:
        return OccupancyGrid.empty(bodies_extent(world.client, obstacles, STATIC_MAP_PAD_M),
                                   DEFAULT_RESOLUTION)
    except GridTooLarge:
        return None


def options_of(settings: LocalizationSpec) -> LocalizationOptions:
    """The filter's options with what a world's ``localization:`` section sets."""
    given = {k: getattr(settings, k) for k in ("min_particles", "max_particles", "update_min_d",
                                               "update_min_a") if getattr(settings, k) is not None}
    return dataclasses.replace(LocalizationOptions(), **given)


def has_laser(robot: Robot) -> bool:
    """Whether the robot's descriptor declares a ``lidar2d`` sensor."""
    return bool(robot.description.sensors)


@dataclass(frozen=True)
class SensorFaults:
    """What the sensor faults of a run (``--inject``) change."""

    odometry: OdometryNoise | None = None
    """Replaces :data:`DEFAULT_ODOMETRY_NOISE`."""
    lidar_sigma: float | None = None
    """Replaces the laser's ``noise_m``."""
    lidar_dropout: float = 0.0
    """Probability of each beam of each scan to be lost."""


@dataclass
class ErrorLog:
    """The believed pose's error against the truth, sampled every tick."""

    errors: list[float] = field(default_factory=list)
    yaw_errors: list[float] = field(default_factory=list)
    time_over: float = 0.0
    """Sim seconds with a position error above :data:`ERROR_THRESHOLD_M`."""
    _last: tuple[float, bool] | None = None

    def sample(self, time: float, believed: Pose, truth: Pose) -> None:
        err = math.hypot(believed[0] - truth[0], believed[1] - truth[1])
        self.errors.append(err)
        self.yaw_errors.append(abs(wrap(believed[2] - truth[2])))
        if self._last is not None and self._last[1]:
            self.time_over += max(0.0, time - self._last[0])
        self._last = (time, err > ERROR_THRESHOLD_M)

    def summary(self) -> dict[str, float]:
        """The report's ``localization`` object (errors in m and rad, time in s)."""
        e = np.asarray(self.errors, dtype=float)
        if e.size == 0:
            e = np.zeros(1)
        yaw = np.asarray(self.yaw_errors or [0.0], dtype=float)
        return {
            "mean_error_m": round(float(e.mean()), 4),
            "p95_error_m": round(float(np.percentile(e, 95)), 4),
            "max_error_m": round(float(e.max()), 4),
            "mean_yaw_error_rad": round(float(yaw.mean()), 4),
            "time_over_0_2m_s": round(self.time_over, 3),
        }


class Localizer:
    """One robot's laser, odometry and particle filter in a run (see the module docstring).

    Args:
        world: the world the robot drives in.
        robot: a robot whose descriptor declares a ``lidar2d`` sensor.
        name: the robot's name in the world (seeds its generators).
        seed: the episode seed.
        settings: the world's ``localization:`` section (defaults without one).
        faults: the sensor faults of the run.
    """

    def __init__(
        self,
        world: World,
        robot: Robot,
        name: str,
        seed: int,
        settings: LocalizationSpec | None = None,
        faults: SensorFaults | None = None,
    ) -> None:
        settings = settings if settings is not None else LocalizationSpec()
        faults = faults if faults is not None else SensorFaults()
        self.world = world
        self.robot = robot
        self.name = name
        self.faults = faults
        spec = robot.description.sensors[0]
        if faults.lidar_sigma is not None:
            spec = dataclasses.replace(spec, noise_m=faults.lidar_sigma)
        self.lidar = Lidar(world, robot, spec, rng=entity_rng(seed, f"lidar:{name}"))
        noise = faults.odometry if faults.odometry is not None else DEFAULT_ODOMETRY_NOISE
        self.odometry = WheelOdometry(robot, noise, rng=entity_rng(seed, f"odometry:{name}"),
                                      time=world.time)
        self.options = options_of(settings)
        # the map is cut where the laser sweeps: what stands at its height is a wall to it
        height = float(self.lidar.sensor_pose()[0][2])
        band = (height - SCAN_HALF_BAND, height + SCAN_HALF_BAND)
        grid = map_from_world(world, resolution=MAP_RESOLUTION, band=band)
        field_ = surface_field(grid, static_outlines(world, band),
                               self.options.laser_likelihood_max_dist)
        self.filter = ParticleFilter(field_, self.options, entity_rng(seed, f"amcl:{name}"))
        given = settings.initial_pose
        start: Pose = ((given.x, given.y, given.yaw) if given is not None
                       else robot.base_pose2d())
        self.filter.set_initial_pose(start, settings.initial_sigmas)
        self.map_to_odom: Pose = compose(start, inverse(self._odom()))
        self.next_scan = world.time
        self.last_scan: Scan | None = None
        self._last_own: np.ndarray | None = None
        """The self filter's beams of :attr:`last_scan` (the costmaps reuse them)."""
        self.errors = ErrorLog()
        self.kidnapped_at: float | None = None
        self._last_update: Pose | None = None
        """Odometry pose of the filter's last update (None: it takes the next scan)."""
        self.overlay: Overlay | None = None
        """Where the scan, the particles and the estimate are drawn after each filter update
        (the run's overlay, which the viewer and the replay read); None draws nothing."""
        frame = static_frame(world)
        self.costmaps: RobotCostmaps | None = (
            RobotCostmaps(frame, start=world.time) if frame is not None else None)
        """The robot's global and local costmaps' obstacle layers, fed from the laser (None:
        the navigator keeps drawing movable objects from the world's geometry)."""
        self._costmap_rng = entity_rng(seed, f"costmap_lidar:{name}")
        self._costmap_scan: tuple[float, Pose] | None = None
        """Sim time and odometry pose of the costmaps' last scan."""
        self._drawn_marks = 0
        """The global obstacle layer's version last drawn on the overlay."""

    def _odom(self) -> Pose:
        o = self.odometry.reading()
        return (o.x, o.y, o.yaw)

    def pose(self) -> Pose:
        """The pose the robot believes it has (map frame): ``map -> odom`` composed with the
        current odometry."""
        return compose(self.map_to_odom, self._odom())

    @property
    def estimate(self) -> PoseEstimate:
        """The filter's last estimate (pose, covariance, lost)."""
        return self.filter.estimate

    def step(self) -> None:
        """Once per tick: integrate the odometry, scan when due, update the filter, sample the
        error."""
        now = self.world.time
        odom = self.odometry.update(now)
        if now >= self.next_scan - 1e-9:
            period = self.lidar.period
            while self.next_scan <= now + 1e-9:
                self.next_scan += period
            if self._moved_enough(odom):
                self._scan_and_update(odom, now)
        if self.costmaps is not None and self.costmaps.due(now):
            last = self._costmap_scan
            scanned = self.last_scan is not None and abs(self.last_scan.time - now) <= 1e-9
            if scanned or last is None or now - last[0] >= STILL_RESCAN_S - 1e-9 or (
                    math.hypot(odom.x - last[1][0], odom.y - last[1][1]) >= STILL_M
                    or abs(wrap(odom.yaw - last[1][2])) >= STILL_RAD):
                self._costmap_scan = (now, (odom.x, odom.y, odom.yaw))
                self._feed_costmaps(now)
        self.errors.sample(now, self.pose(), self.robot.base_pose2d())

    def _feed_costmaps(self, now: float) -> None:
        """Give the costmaps due now the latest scan (see the module docstring)."""
        assert self.costmaps is not None
        scan, own = self.last_scan, self._last_own
        if scan is None or own is None or abs(scan.time - now) > 1e-9:
            scan = self.lidar.scan(self.faults.lidar_dropout, rng=self._costmap_rng)
            own = self._own_returns(scan)
        returned = ~scan.no_return & ~own
        pose = self.pose()
        sensor = compose(pose, scan.sensor_pose)
        self.costmaps.take(now, (pose[0], pose[1]), sensor, scan.angles, scan.ranges, returned)
        version = self.costmaps.global_layer.version
        if version != self._drawn_marks and self.overlay is not None:
            self._drawn_marks = version  # marked, cleared by a scan or by a clear node
            self.draw_marks(self.overlay)

    def draw_marks(self, overlay: Overlay) -> None:
        """Draw the global costmap's marks on ``overlay`` (orange, just above the floor; at most
        :data:`MARKS_DRAWN` of them, every k-th)."""
        assert self.costmaps is not None
        pts = self.costmaps.global_layer.points()
        step = max(1, -(-len(pts) // MARKS_DRAWN))
        overlay.show_points(f"{self.name}_costmap_marks", pts[::step], z=0.02, rgba=MARK_COLOUR,
                            size=0.05)

    def _moved_enough(self, odom: Odometry) -> bool:
        """Whether the filter would take a scan now: none taken since its start, or the
        odometry travelled ``update_min_d`` or turned ``update_min_a`` since its last one (the
        scans it would drop are not cast: the run goes faster, and draws the same)."""
        last = self._last_update
        if last is None:
            return True
        moved = math.hypot(odom.x - last[0], odom.y - last[1])
        turned = abs(wrap(odom.yaw - last[2]))
        return moved >= self.options.update_min_d or turned >= self.options.update_min_a

    def _scan_and_update(self, odom: Odometry, now: float) -> None:
        """Scan, give the scan to the filter, and set ``map -> odom`` from its estimate."""
        scan = self.lidar.scan(self.faults.lidar_dropout)
        self.last_scan = scan
        self._last_own = own = self._own_returns(scan)
        ranges = np.where(own, scan.range_max, scan.ranges)
        reading = FilterScan(ranges, scan.angle_min, scan.angle_increment, scan.range_max,
                             sensor_pose=scan.sensor_pose, time=now)
        if self.filter.update(OdomPose(odom.x, odom.y, odom.yaw, now), reading):
            est = self.filter.estimate
            self.map_to_odom = compose((est.x, est.y, est.yaw),
                                       inverse((odom.x, odom.y, odom.yaw)))
            self._last_update = (odom.x, odom.y, odom.yaw)
            if self.overlay is not None:
                self.draw(self.overlay, scan)

    def _own_returns(self, scan: Scan) -> np.ndarray:
        """The beams of ``scan`` that end on the robot itself or on what it holds (a self
        filter): nearer than :data:`MIN_RETURN_M`, or within :data:`SELF_FILTER_PADDING` of
        where the robot's own model, in its current joint state with its held objects,
        stops the beam. A load carried across the scan plane is not a wall to the filter."""
        own = scan.ranges < MIN_RETURN_M
        bodies = [self.robot.body] + [a.object_body
                                      for a in self.world.attachments.held_by(self.name)]
        model = self.lidar.model_ranges(bodies)
        own |= scan.ranges >= model - SELF_FILTER_PADDING
        own &= ~scan.no_return
        return own

    def draw(self, overlay: Overlay, scan: Scan) -> None:
        """Draw on ``overlay``: the scan's returns where the robot believes it is (red, at the
        scan plane), the particles (blue, at most :data:`PARTICLES_DRAWN`) and the estimate
        (a frame at the believed pose; the robot itself is drawn at its true pose)."""
        x, y, yaw = self.pose()
        sx, sy, syaw = scan.sensor_pose
        ox, oy, oyaw = compose((x, y, yaw), (sx, sy, syaw))
        pts = scan.points()
        c, s = math.cos(oyaw), math.sin(oyaw)
        world = np.column_stack([ox + c * pts[:, 0] - s * pts[:, 1],
                                 oy + s * pts[:, 0] + c * pts[:, 1]])
        height = float(self.lidar.sensor_pose()[0][2])
        overlay.show_points(f"{self.name}_laser_scan", world, z=height, rgba=SCAN_COLOUR,
                            size=0.05)
        poses = self.filter.particles.poses
        step = max(1, len(poses) // PARTICLES_DRAWN)
        overlay.show_points(f"{self.name}_particles", poses[::step, :2], z=0.05,
                            rgba=PARTICLE_COLOUR, size=0.04)
        frame = np.eye(4)
        frame[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
        frame[:3, 3] = (x, y, 0.05)
        overlay.show_frame(f"{self.name}_pose_estimate", frame, size=0.4)

    def reset(self, pose: Pose, sigmas: Pose | None = None) -> None:
        """Start the filter again from ``pose`` (SetInitialPose); the belief jumps there."""
        self.filter.set_initial_pose(pose, sigmas)
        self.map_to_odom = compose(pose, inverse(self._odom()))
        self._last_update = None

    def global_localization(self) -> None:
        """Spread the particles over the map's free space (ReinitializeGlobalLocalization);
        the belief stays where it was until the filter has taken a scan."""
        self.filter.global_localization()
        self._last_update = None


class RunLocalization:
    """The localisers of a run, one per robot with a laser, stepped before every tick
    (``run_localization(runner)``), and the faults due at a sim time (a kidnap)."""

    def __init__(self, localizers: dict[str, Localizer]) -> None:
        self.localizers = localizers
        self.before_step: list[KidnapAt] = []
        """Callables ``f(run_localization)`` run before the localisers step (world faults that
        are due at a sim time, such as a kidnap)."""

    def __call__(self, runner: Any = None) -> None:
        """Step every localiser (the run loop calls this before each tick)."""
        for hook in self.before_step:
            hook(self)
        for loc in self.localizers.values():
            loc.step()

    def get(self, name: str) -> Localizer | None:
        """The localiser of robot ``name`` (or of the only robot for ""), None without one."""
        if name in self.localizers:
            return self.localizers[name]
        if not name and len(self.localizers) == 1:
            return next(iter(self.localizers.values()))
        return None

    def report(self) -> dict[str, float]:
        """The report's ``localization`` object: the first robot's errors (one robot localises
        in every shipped world)."""
        first = next(iter(self.localizers.values()))
        return first.errors.summary()

    def costmap_report(self) -> dict[str, int] | None:
        """The report's ``costmap`` object: the first robot's costmaps
        (:meth:`~bt_manip.navigation.layered.RobotCostmaps.report`); None without them."""
        first = next(iter(self.localizers.values()))
        return first.costmaps.report() if first.costmaps is not None else None


class KidnapAt:
    """The ``kidnap:T`` fault of a run: due once, at the first step at or after sim time T."""

    def __init__(self, at: float, injector: FaultInjector, seed: int) -> None:
        self.at = at
        self.injector = injector
        self.rng = entity_rng(seed, f"kidnap:{at:g}")
        self.done = False

    def __call__(self, run: RunLocalization) -> None:
        if self.done:
            return
        loc = next(iter(run.localizers.values()))
        if loc.world.time < self.at - 1e-9:
            return
        self.done = True
        result = kidnap(loc.world, loc.robot, loc.name, self.rng)
        loc.kidnapped_at = loc.world.time
        self.injector.events.append(FaultEvent(KIDNAP, loc.name, loc.world.time, result.note))


def localization_for_run(
    world: World | None, seed: int, localize: bool, injector: FaultInjector
) -> RunLocalization | None:
    """The run's localisation: on with ``--localize`` (``localize``) or a ``localization:``
    section in the world file; None when off (nothing is built, nothing drawn).

    Raises :class:`~bt_manip.errors.InputError` for localisation asked of a run without a
    world or of a world whose robots have no laser, and for a fault that needs localisation
    in a run without it."""
    section = world.spec.localization if world is not None else None
    on = localize or section is not None
    needing = localization_faults(injector.specs)
    if not on:
        if needing:
            raise InputError([Problem(
                "--inject", None,
                f"'{f.text()}' acts on the robot's localisation, which is off: run with "
                "--localize (or give the world a localization: section)") for f in needing])
        return None
    if world is None:
        raise InputError.single("--localize", None, "localisation needs a world (--world W)")
    robots = {name: r for name, r in world.robots.items()
              if has_laser(r) and (r.has_wheels or r.is_holonomic)}
    if not robots:
        listed = ", ".join(f"{n} ({r.description.name})" for n, r in world.robots.items())
        why = (f"no robot of {world.path.name} has a lidar2d sensor (robots: {listed or 'none'});"
               " declare one under sensors: in the robot's descriptor (bt-manip robot init "
               "--lidar LINK writes one)")
        if localize:
            raise InputError.single("--localize", None, why)
        raise InputError.single(str(world.path), section.line if section else None, why)
    faults = SensorFaults()
    for f in needing:
        if f.kind == ODOM_NOISE:
            k, k_rot = f.values
            faults = dataclasses.replace(faults, odometry=OdometryNoise(k, k_rot, k))
        elif f.kind == LIDAR_NOISE:
            faults = dataclasses.replace(faults, lidar_sigma=f.values[0])
        elif f.kind == LIDAR_DROPOUT:
            faults = dataclasses.replace(faults, lidar_dropout=f.values[0])
    run = RunLocalization({name: Localizer(world, r, name, seed, section, faults)
                           for name, r in robots.items()})
    for f in needing:
        if f.kind == KIDNAP:
            run.before_step.append(KidnapAt(f.values[0], injector, seed))
    return run
