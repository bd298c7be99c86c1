"""Navigation of one robot in one PyBullet world: map, footprint, planner and follower.

A :class:`Navigator` rasterises the static obstacles once, redraws the movable objects when
asked (they may have moved), keeps the robot's planning footprint (which grows while it holds
an object, see :meth:`Navigator.attach`) and drives a follower.

It never commands the robot itself. Per tick the caller does::

    status = nav.update(robot.base_pose2d(), world.clock.now())
    robot.set_base_twist(*status.cmd)

and stops when ``status.state`` is SUCCEEDED or FAILED (``status.reason`` says why).

- Bare robot: grid A* for the footprint's half width, line-of-sight shortcuts, and a
  :class:`PathFollower`. While the robot drives, the follower asks every ``replan_period``
  seconds whether a movable object now blocks the rest of the path; if so the navigator plans
  again from where the robot is.
- Carrying something: the grid plan first tells whether any way is wide enough for the whole
  footprint against every obstacle; when none is but one is among the obstacles that reach
  the load (it is carried over the low ones, such as the stand it was lifted from), the search
  over poses below decides; otherwise, or when that search finds nothing, the plan fails with
  the footprint as the reason. Then a search over poses
  (:mod:`bt_manip.navigation.lattice`) finds moves, backing up where needed, that keep the whole
  robot and its load clear, and a :class:`SegmentFollower` drives them. When one of its runs
  ends off its pose, the same search plans the rest of the way again from where the robot
  stands (moved objects are not watched for in this mode).

With costmap layers (``layers``: the robot's
:class:`~bt_manip.navigation.layered.RobotCostmaps`, given when the run localises), the movable
objects are not drawn from the world's geometry as they move: the map the planners read is the
static grid with the global costmap's laser marks drawn in
(:func:`bt_manip.navigation.layers.compose`), inflated. The objects the robot was told of
(``known``: the world file's objects, as a site plan gives them) are drawn once, where they
stand when the navigator is built, and stay there in its map (a prior map: moving them later
does not move them there) until the robot picks one up; that is how an object the laser cannot
see (lower than its scan plane, as Scenario A's panel on its stand) is still planned round.
Objects that appear during the run (a dropped crate, a spawned model) are known only from the
laser; the carrying robot's chassis slab gets the marks too (a mark says something stands at
the laser's height, which the chassis reaches; whether it reaches the load, a planar laser cannot
tell). The bare robot's blocked-path check reads the local costmap (the rolling window): the
path ahead is blocked when it passes within the footprint's half width of a local mark, and the
plan is made again on the global costmap.

Where a skid-steer base turns on the spot (``pivot``) matters for ending on the goal; see
:mod:`bt_manip.navigation.controller`.

A holonomic base (``base.type: holonomic``) is planned on the same grid as a disc of its
footprint's turning radius (it may turn anywhere on the way), carrying or not, and followed by
a :class:`~bt_manip.navigation.holonomic.HolonomicFollower`; the search over poses is for
skid-steer bases only.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from bt_manip.navigation.controller import (
    FollowerOptions,
    FollowState,
    FollowStatus,
    PathFollower,
    Pose2D,
)
from bt_manip.navigation.costmap import CostMap, InflationOptions, clearance
from bt_manip.navigation.distance import squared_distances
from bt_manip.navigation.footprint import PlanarFootprint
from bt_manip.navigation.grid import DEFAULT_RESOLUTION, OccupancyGrid, bodies_extent, rasterise
from bt_manip.navigation.holonomic import HolonomicFollower, base_limited, turning_footprint
from bt_manip.navigation.lattice import LatticeOptions, PosePlan, plan_poses
from bt_manip.navigation.layered import RobotCostmaps
from bt_manip.navigation.layers import compose
from bt_manip.navigation.planner import NavPlan, PlannerOptions, PlanOutcome, plan_path
from bt_manip.navigation.segments import SegmentFollower
from bt_manip.navigation.shapes import ZBand, body_outlines, planar_frame
from bt_manip.navigation.smoothing import densify, path_length
from bt_manip.sim import pybullet_queries as pbq


@dataclass(frozen=True)
class NavigatorOptions:
    """Grid, inflation, planning and following options."""

    resolution: float = DEFAULT_RESOLUTION
    band: ZBand | None = None
    """Height band (m) of the obstacles that matter; default from 2 cm to 5 cm above the
    robot's highest point at construction."""
    inflation: InflationOptions = field(default_factory=InflationOptions)
    planner: PlannerOptions = field(default_factory=PlannerOptions)
    follower: FollowerOptions = field(default_factory=FollowerOptions)
    lattice: LatticeOptions = field(default_factory=LatticeOptions)
    pivot: float | None = None
    """Where the base turns about on the spot (m ahead of the base frame); ``None`` takes the
    descriptor's ``base.pivot_offset`` if it has one, else 0."""


LATTICE_FLOAT_CELLS = 1 << 22
"""Up to this many cells, the pose search reads a float64 clearance grid (8 bytes per cell);
beyond, the squared cell distances (4 bytes per cell, the same clearances, a little more work
per look-up)."""


def lattice_clearance(grid: OccupancyGrid, d2: np.ndarray | None = None) -> np.ndarray:
    """What the pose search checks footprints against for ``grid`` (``d2``: its squared cell
    distances if known): a clearance grid on small grids, the squared distances on large ones,
    a read-only view of ``inf`` when nothing is occupied."""
    if grid.occupied.size <= LATTICE_FLOAT_CELLS:
        return clearance(grid)
    if d2 is None:
        d2 = squared_distances(grid.occupied)
    if d2 is None:
        return np.broadcast_to(np.float64(np.inf), grid.shape)
    return d2


def split_links(robot: Any) -> tuple[list[int], list[int]]:
    """The robot's links the arm does not move (root included) and those it moves."""
    arm = robot.arm_link_ids()
    n = pbq.joint_count(robot.client, robot.body)
    return [-1, *(j for j in range(n) if j not in arm)], arm


def robot_top(robot: Any) -> float:
    """Highest point (m) of the robot's collision geometry now."""
    top = 0.0
    for link in range(-1, pbq.joint_count(robot.client, robot.body)):
        top = max(top, pbq.aabb(robot.client, robot.body, link).upper[2])
    return float(top)


MAP_PAD = 0.5
"""Free floor (m) the map keeps round the obstacles, before the room to drive round them."""
MAP_ALIGN = 0.1
"""The map's margin is a whole number of these (m): a multiple of the grid's cells and of the
pose search's bins, so a wider margin leaves every cell and bin where it was."""


def map_extent(client: int, obstacles: Sequence[int], robot_xy: Sequence[float],
               footprint: PlanarFootprint) -> tuple[float, float, float, float] | None:
    """The map's rectangle: the obstacles' extent with :data:`MAP_PAD` of free floor round it
    (None without obstacles: :func:`rasterise` says so), or, for a robot that stands outside the
    obstacles' extent (a world open round a lone wall or a row of columns), a margin with
    room to drive round the outermost obstacle too (the footprint's turning diameter and a
    cell, in whole :data:`MAP_ALIGN` steps, so cells and pose bins stay where they were),
    grown to hold the robot."""
    if not obstacles:
        return None
    x0, y0, x1, y1 = bodies_extent(client, obstacles, 0.0)
    x, y = float(robot_xy[0]), float(robot_xy[1])
    if x0 <= x <= x1 and y0 <= y <= y1:
        return x0 - MAP_PAD, y0 - MAP_PAD, x1 + MAP_PAD, y1 + MAP_PAD
    room = 2.0 * footprint.circumradius + 0.05
    pad = round(MAP_PAD + math.ceil(room / MAP_ALIGN - 1e-9) * MAP_ALIGN, 9)
    return (min(x0, x) - pad, min(y0, y) - pad, max(x1, x) + pad, max(y1, y) + pad)


class Navigator:
    """Map, footprint and path following for ``robot`` among ``obstacles`` and ``movable``.

    Args:
        robot: a :class:`bt_manip.sim.robot.Robot` (its client, body and descriptor are used).
        obstacles: body ids of the static structure and furniture.
        movable: body ids (or name -> id) of objects that may move; redrawn on refresh.
        layers: the robot's laser-fed costmaps; with them the movable objects are not drawn,
            the global costmap's marks are (see the module docstring).
        known: with ``layers``, the movable objects the robot was told of, drawn where they
            stand now until it picks one up.
    """

    def __init__(
        self,
        robot: Any,
        obstacles: Sequence[int],
        movable: Mapping[str, int] | Sequence[int] = (),
        options: NavigatorOptions = NavigatorOptions(),
        layers: RobotCostmaps | None = None,
        known: Sequence[int] = (),
    ) -> None:
        self.robot = robot
        self.layers = layers
        self._layers_drawn: tuple[int, frozenset[int]] | None = None
        """The global obstacle layer's version and the known objects drawn on
        :attr:`costmap`."""
        self.client = robot.client
        self.options = options
        self._follower_options: FollowerOptions = options.follower
        """The follower options of the navigation under way (see :meth:`start`)."""
        self.movable: dict[int, str] = (
            {b: n for n, b in movable.items()}
            if isinstance(movable, Mapping)
            else {b: f"body {b}" for b in movable}
        )
        self.band: ZBand = options.band or (0.02, robot_top(robot) + 0.05)
        self.base_footprint = PlanarFootprint.of_robot(robot, band=self.band)
        self.static: OccupancyGrid = rasterise(
            self.client,
            list(obstacles),
            resolution=options.resolution,
            band=self.band,
            extent=map_extent(self.client, list(obstacles), robot.base_pose2d()[:2],
                              self.base_footprint),
            remember=False,
        )
        self.known: dict[int, np.ndarray] = {}
        """With layers: per object the robot was told of and has not picked up, the flat
        indices of its cells when the navigator was built."""
        if layers is not None:
            for body in known:
                parts = [self.static.cells_of(o) for o in body_outlines(self.client, body,
                                                                        self.band)]
                if parts:
                    self.known[body] = np.unique(np.concatenate(parts))
        self.footprint = self.base_footprint
        self.attached: dict[int, str] = {}
        self.costmap = CostMap(self._compose(), options.inflation)
        self.follower: PathFollower | SegmentFollower | HolonomicFollower | None = None
        self.holonomic = robot.description.base.type == "holonomic"
        self.poses: PosePlan | None = None
        self._obstacles = list(obstacles)
        self._carry: tuple | None = None
        self._carry_high: OccupancyGrid | None = None
        """The obstacles that reach the carried load's height (None: nothing carried)."""
        self.plan: NavPlan | None = None
        self._goal: Pose2D | None = None
        self._plan_cost: np.ndarray | None = None
        self._align = True
        self.pivot = (
            options.pivot
            if options.pivot is not None
            else float(getattr(robot.description.base, "pivot_offset", 0.0))
        )
        """Where the base turns about on the spot (m ahead of its frame)."""

    # -- map --------------------------------------------------------------------------------
    def _movable_cells(self) -> dict[int, np.ndarray]:
        """Per movable object not carried, the flat indices of the cells it occupies now (none
        with costmap layers: the laser marks them)."""
        cells: dict[int, np.ndarray] = {}
        if self.layers is not None:
            return cells
        for body in self.movable:
            if body not in self.attached:
                outlines = body_outlines(self.client, body, self.band)
                parts = [self.static.cells_of(o) for o in outlines]
                cells[body] = np.unique(np.concatenate(parts)) if parts else np.zeros(0, np.int64)
        return cells

    def _compose(self, cells: dict[int, np.ndarray] | None = None) -> OccupancyGrid:
        """The static grid with the movable objects drawn in (the static grid itself, not a
        copy, when there are none: it is never drawn on). With costmap layers, the static grid
        with the global costmap's marks."""
        if self.layers is not None:
            self._layers_drawn = self._layers_key()
            grid = compose(self.static, self.layers.global_layer)
            if not self.known:
                return grid
            if grid is self.static:
                grid = OccupancyGrid(grid.origin, grid.resolution, grid.occupied.copy(),
                                     grid.band)
            flat = grid.occupied.reshape(-1)
            for idx in self.known.values():
                flat[idx] = True
            return grid
        if cells is None:
            cells = self._movable_cells()
        if not cells:
            return self.static
        s = self.static
        grid = OccupancyGrid(s.origin, s.resolution, s.occupied.copy(), s.band)
        flat = grid.occupied.reshape(-1)
        for body, idx in cells.items():
            flat[idx] = True
            grid.sources[body] = idx
        return grid

    def refresh(self) -> bool:
        """Redraw the movable objects (with costmap layers: the global costmap's marks); True if
        the occupied cells changed."""
        if self.layers is not None:
            if self._layers_key() == self._layers_drawn:
                return False
            old_occupied = self.costmap.grid.occupied
            grid = self._compose()
            if np.array_equal(grid.occupied, old_occupied):
                return False
            self.costmap = self.costmap.with_grid(grid)
            return True
        cells = self._movable_cells()
        old = self.costmap.grid
        if cells.keys() == old.sources.keys() and all(
            np.array_equal(idx, old.sources[b]) for b, idx in cells.items()
        ):
            return False  # the same cells drawn on the same static grid
        grid = self._compose(cells)
        if np.array_equal(grid.occupied, old.occupied):
            return False
        self.costmap = self.costmap.with_grid(grid)
        return True

    def _layers_key(self) -> tuple[int, frozenset[int]]:
        assert self.layers is not None
        return (self.layers.global_layer.version, frozenset(self.known))

    @property
    def planning_footprint(self) -> PlanarFootprint:
        """What the grid planner clears: the footprint, or the disc it sweeps when a holonomic
        base turns on the way."""
        return turning_footprint(self.footprint) if self.holonomic else self.footprint

    @property
    def cost(self) -> np.ndarray:
        """The cost grid the planner searches for the current footprint."""
        return self.costmap.cost_for(self.planning_footprint)

    # -- what the robot carries --------------------------------------------------------------
    def attach(self, body: int, name: str | None = None) -> PlanarFootprint:
        """Count ``body`` (held by the robot) as part of the footprint, where it sits now.

        While something is carried, goals are planned over poses (:mod:`.lattice`) with the
        robot and the load checked in two height slabs: below the load's bottom (wheels and
        base against every obstacle) and above it (arm and load against the obstacles that
        reach that high).
        """
        label = name or self.movable.get(body, f"body {body}")
        self.attached[body] = label
        self.known.pop(body, None)  # it has been taken from where the map had it
        self.footprint = self.footprint.with_body(self.robot, body, label, band=self.band)
        self.refresh()
        self._build_carry_layers()
        return self.footprint

    def detach(self, body: int) -> PlanarFootprint:
        """Stop counting ``body`` as carried; it becomes an obstacle again if movable."""
        self.attached.pop(body, None)
        fp = self.base_footprint
        for b, label in self.attached.items():
            fp = fp.with_body(self.robot, b, label, band=self.band)
        self.footprint = fp
        self.refresh()
        self._build_carry_layers()
        return fp

    def _build_carry_layers(self) -> None:
        """The two layers a carrying robot is planned in: its chassis (wheels and body) against
        every obstacle up to the chassis top, and its arm with the load against the obstacles
        that reach above the lowest point of the arm or load (an arm held over a low obstacle
        does not collide with it)."""
        self._carry = None
        self._carry_high = None
        if not self.attached or self.holonomic:
            return
        c = self.client
        robot = self.robot
        chassis, arm = split_links(robot)
        top = max(self.band[1], *(pbq.aabb(c, b).upper[2] for b in self.attached))
        low_top = max(pbq.aabb(c, robot.body, link).upper[2] for link in chassis)
        low_top += 0.02
        arm_bottom = min(
            [pbq.aabb(c, robot.body, link).lower[2] for link in arm]
            + [pbq.aabb(c, b).lower[2] for b in self.attached]
        )
        high_band = (max(self.band[0], arm_bottom - 0.03), top + 0.05)
        frame = planar_frame(*robot.base_pose2d())
        described = PlanarFootprint.from_description(robot.description.footprint, "")
        low_parts = body_outlines(
            c, robot.body, (self.band[0], low_top), reference=frame, links=chassis
        )
        low_fp = PlanarFootprint(described.outlines + tuple(low_parts), self.base_footprint.label)
        high_parts = body_outlines(c, robot.body, high_band, reference=frame, links=arm)
        for b in self.attached:
            high_parts += body_outlines(c, b, high_band, reference=frame)
        high_fp = PlanarFootprint(tuple(high_parts), " + ".join(self.attached.values()))
        movers = [] if self.layers is not None else [
            b for b in self.movable if b not in self.attached]
        bodies = list(self._obstacles) + movers
        ext = self.static.extent
        res = self.options.resolution
        low = rasterise(
            c, bodies, resolution=res, band=(self.band[0], low_top), extent=ext, remember=False
        )
        if self.layers is not None:  # the same origin and cell side as the static grid
            marks = self.layers.global_layer.marked
            r, k = min(low.shape[0], marks.shape[0]), min(low.shape[1], marks.shape[1])
            low.occupied[:r, :k] |= marks[:r, :k]
            if low.shape == self.static.shape:
                flat = low.occupied.reshape(-1)
                for idx in self.known.values():
                    flat[idx] = True
        high = rasterise(c, bodies, resolution=res, band=high_band, extent=ext, remember=False)
        self._carry = (low_fp, high_fp, low, lattice_clearance(low), lattice_clearance(high))
        self._carry_high = high

    def carry_layers(self) -> tuple | None:
        """The carrying robot's layers (chassis footprint, arm-and-load footprint, chassis grid,
        its clearance, the upper slab's clearance) rebuilt where the movable objects are now;
        None when nothing is carried or the base is holonomic."""
        self._build_carry_layers()
        return self._carry

    # -- planning and following ---------------------------------------------------------------
    def plan_to(self, start: Pose2D, goal: Pose2D) -> NavPlan:
        """A plan from ``start`` to ``goal`` for the current footprint and map."""
        return plan_path(
            self.costmap, self.planning_footprint, start[:2], goal[:2], self.options.planner
        )

    def start(
        self,
        pose: Pose2D,
        goal: Pose2D,
        align: bool = True,
        follower: FollowerOptions | None = None,
    ) -> NavPlan:
        """Plan from ``pose`` to ``goal`` (x, y, yaw) and get ready to follow the path.

        ``follower`` (tolerances, speeds) holds for this navigation only; without it the
        navigator's ``options.follower`` applies. Returns the plan; when it is not ``ok`` there
        is nothing to follow and :meth:`update` answers FAILED with the plan's reason.
        """
        self._follower_options = follower if follower is not None else self.options.follower
        self.refresh()
        if self._carry is not None:
            # the layers the carrying robot is planned in hold the movable objects where they
            # are now (a crate may have fallen since the load was attached)
            self._build_carry_layers()
        self._goal = goal
        self._align = align
        self.follower = None
        if self.holonomic:
            return self._start_holonomic(pose, goal, align)
        self.plan = self.plan_to(self._pivot(pose), self._pivot_goal())
        if not self.plan.ok:
            self.plan = self.plan_to(pose, goal)  # the reason, in the caller's coordinates
            if not self.plan.ok:
                if self.plan.outcome is PlanOutcome.FOOTPRINT and self._carry is None:
                    # the grid is inflated for turning anywhere; over poses the robot may
                    # still drive straight through a narrow doorway
                    grid = self.costmap.grid
                    clear = lattice_clearance(grid, self.costmap.d2)
                    return self._follow_poses(pose, goal, self.footprint, grid, clear)
                if self.plan.outcome is PlanOutcome.FOOTPRINT:
                    # the grid holds the whole load against every obstacle, also the low ones
                    # it is carried over (the stand it was lifted out of): when a way is wide
                    # enough among the obstacles that reach the load, the search over poses
                    # checks the chassis and the load in their own height slabs
                    grid_plan = self.plan
                    if self._load_fits(pose) and self._start_carrying(pose, goal).ok:
                        return self.plan
                    self.plan = grid_plan  # the grid's reason says what is too wide
                return self.plan
        if self._carry is not None:
            return self._start_carrying(pose, goal)
        self._plan_cost = self.cost
        self.follower = PathFollower(
            cast(np.ndarray, self.plan.polyline),  # an OK plan has its polyline
            goal if align else goal[:2],
            dataclasses.replace(self._follower_options, pivot=self.pivot),
            path_blocked=self._path_blocked,
            replan=self._replan,
        )
        return self.plan

    def _start_holonomic(self, pose: Pose2D, goal: Pose2D, align: bool) -> NavPlan:
        """Plan for the turning disc and get a holonomic follower ready."""
        self.plan = self.plan_to(pose, goal)
        if self.plan.ok:
            self._plan_cost = self.cost
            self.follower = HolonomicFollower(
                cast(np.ndarray, self.plan.polyline),
                goal if align else goal[:2],
                base_limited(self._follower_options, self.robot.description.base),
                path_blocked=self._path_blocked,
                replan=self._replan,
            )
        return self.plan

    def _load_fits(self, pose: Pose2D) -> bool:
        """Whether the grid plan finds a way wide enough for the whole footprint among the
        obstacles that reach up to the load (those of the carrying robot's upper slab)."""
        if self._carry_high is None:
            return False
        costmap = CostMap(self._carry_high, self.options.inflation)
        plan = plan_path(
            costmap, self.footprint, self._pivot(pose)[:2], self._pivot_goal()[:2],
            self.options.planner,
        )
        return plan.ok

    def _start_carrying(self, pose: Pose2D, goal: Pose2D) -> NavPlan:
        """Plan over poses for the robot with its load; the grid plan said a way may exist."""
        assert self._carry is not None
        low_fp, high_fp, low, clear_low, clear_high = self._carry
        return self._follow_poses(pose, goal, low_fp, low, clear_low, high_fp, clear_high)

    def _follow_poses(
        self,
        pose: Pose2D,
        goal: Pose2D,
        footprint: PlanarFootprint,
        grid: OccupancyGrid,
        clear: np.ndarray,
        carried: PlanarFootprint | None = None,
        clear_high: np.ndarray | None = None,
    ) -> NavPlan:
        """Plan over poses with ``footprint`` (and ``carried``) and get ready to follow."""

        def plan_from(start: Pose2D) -> PosePlan:
            return plan_poses(
                grid,
                clear,
                footprint,
                start,
                goal,
                self.pivot,
                self.options.lattice,
                carried=carried,
                clear_high=clear_high,
            )

        def replan(start: Pose2D) -> PosePlan:
            new = plan_from(start)
            if new.ok:
                self.poses = new
            return new

        poses = plan_from(pose)
        if not poses.ok:
            self.plan = NavPlan(PlanOutcome.FOOTPRINT, poses.reason)
            return self.plan
        assert poses.poses is not None
        p = self.pivot
        pts = poses.poses
        poly = densify(
            np.column_stack([pts[:, 0] + p * np.cos(pts[:, 2]), pts[:, 1] + p * np.sin(pts[:, 2])]),
            self.options.planner.spacing,
        )
        self.plan = NavPlan(PlanOutcome.OK, "ok", poly, None, path_length(poly))
        self.poses = poses
        self.follower = SegmentFollower(
            poses,
            goal,
            dataclasses.replace(self._follower_options, pivot=self.pivot),
            replan=replan,
        )
        return self.plan

    def update(self, pose: Pose2D, now: float) -> FollowStatus:
        """One tick: the twist to apply, or SUCCEEDED / FAILED with the reason."""
        if self.follower is None:
            reason = self.plan.reason if self.plan is not None else "no goal given"
            return FollowStatus(FollowState.FAILED, reason, (0.0, 0.0))
        return self.follower.update(pose, now)

    def _cells(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        grid = self.costmap.grid
        rows = np.floor((points[:, 1] - grid.origin[1]) / grid.resolution).astype(int)
        cols = np.floor((points[:, 0] - grid.origin[0]) / grid.resolution).astype(int)
        r, c = grid.shape
        return np.clip(rows, 0, r - 1), np.clip(cols, 0, c - 1)

    def _path_blocked(self, ahead: np.ndarray) -> bool:
        if self.layers is not None:
            self.refresh()
            return self.layers.local.first_in_way(ahead,
                                                  self.planning_footprint.half_width) is not None
        if not self.movable or not self.refresh():
            return False
        rows, cols = self._cells(ahead)
        now = self.cost[rows, cols]
        before = (
            self._plan_cost[rows, cols]
            if self._plan_cost is not None and self._plan_cost.shape == self.cost.shape
            else np.ones_like(now)
        )
        return bool(np.any(np.isinf(now) & np.isfinite(before)))

    def _pivot(self, pose: Pose2D) -> Pose2D:
        """Where the base's pivot point is for a base pose (the heading is kept)."""
        p = self.pivot
        return (pose[0] + p * math.cos(pose[2]), pose[1] + p * math.sin(pose[2]), pose[2])

    def _pivot_goal(self) -> Pose2D:
        """Where the pivot must end: ahead of the goal along its heading when aligning."""
        assert self._goal is not None
        return self._pivot(self._goal) if self._align else self._goal

    def _replan(self, pose: Pose2D) -> np.ndarray | str:
        assert self._goal is not None
        plan = self.plan_to(self._pivot(pose), self._pivot_goal())
        if not plan.ok:
            return plan.reason
        self.plan = plan
        self._plan_cost = self.cost
        return cast(np.ndarray, plan.polyline)  # an OK plan has its polyline
