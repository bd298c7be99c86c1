"""The run context: every service of one run that robot behaviours reach, in typed fields.

:class:`RunContext` is the tree's :class:`~bt_manip.bt.context.TreeContext` (clock, world,
timers) plus what a run with a world adds:

- ``faults``: the run's :class:`~bt_manip.run.faults.FaultInjector` (None: no faults
  injected);
- ``overlay``: the :class:`~bt_manip.overlay.Overlay` that behaviours draw on and viewers read;
- :meth:`RunContext.robot_services`: per robot, its navigator and arm IK, built on first use
  and kept for the rest of the run;
- ``running``: the robot actions RUNNING now (:class:`RunningActions`), so that a node can
  cancel another node's action (Nav2's Cancel* nodes).

The episode (:mod:`bt_manip.episode`) builds one per run; a Python-authored tree that acts on a
world is given one with :meth:`RunContext.for_world`. Nothing of a run is kept on the simulator's
objects: a second run on the same world starts with fresh services.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

from bt_manip.bt.context import TreeContext
from bt_manip.kinematics import ArmModel, IKOptions, IKSolver
from bt_manip.navigation.navigator import Navigator
from bt_manip.overlay import Overlay, run_overlay

if TYPE_CHECKING:
    from bt_manip.localization.runtime import Localizer, RunLocalization
    from bt_manip.run.faults import FaultInjector
    from bt_manip.sim.robot import Robot
    from bt_manip.sim.world import World

__all__ = [
    "IK_MAX_RESTARTS", "IK_POSTURE_WEIGHT", "IK_TOLERANCE", "ArmIK", "Cancellable",
    "RobotServices", "RunContext", "RunningActions", "run_overlay",
]

IK_TOLERANCE = 1e-4
"""Position (m) and rotation (rad) tolerance of the IK targets of behaviours."""
IK_MAX_RESTARTS = 200
"""Seeded restarts an IK solve may take (no wall-clock budget: the same run, the same joints)."""
IK_POSTURE_WEIGHT = 0.05
"""Pull of the IK towards its seed posture."""


@dataclass
class ArmIK:
    """The kinematic model of a robot's arm to one tip frame, with its solvers."""

    model: ArmModel
    full: IKSolver
    free_yaw: IKSolver


@dataclass
class RobotServices:
    """What one robot's behaviours share during a run: its navigator and its arm IK."""

    world: World
    robot: Robot
    localizer: Localizer | None = None
    """The robot's localisation when the run localises (None: it drives on ground truth)."""
    _navigator: Navigator | None = field(default=None, init=False, repr=False)
    _arm_iks: dict[str, ArmIK] = field(default_factory=dict, init=False, repr=False)
    arm_planner: Any = field(default=None, init=False, repr=False)
    """The arm's planning scene and planner
    (:class:`~bt_manip.manipulation.arm_planner.ArmPlanner`), made by the first node that
    plans."""

    @property
    def navigator(self) -> Navigator:
        """The robot's navigator, built on first use from the world's static obstacles (and,
        when the robot localises, on its laser-fed costmap layers: the world file's objects are
        then known where they stood when it was built, until picked up, and everything else
        where the laser has marked it).

        Raises :class:`~bt_manip.navigation.grid.GridTooLarge` when the world is too large to
        be mapped.
        """
        if self._navigator is None:
            layers = self.localizer.costmaps if self.localizer is not None else None
            movable = self.world.movable
            declared = [movable[o.name] for o in self.world.spec.objects if o.name in movable]
            self._navigator = Navigator(
                self.robot, self.world.obstacle_body_ids(), movable, layers=layers,
                known=declared,
            )
        return self._navigator

    def believed_pose(self) -> tuple[float, float, float]:
        """The pose (x, y, yaw; map frame) the robot believes its base has: the localisation's
        estimate when the run localises, else the ground truth. Navigation plans, steers and
        checks its goals on this; physics and reports keep the ground truth."""
        if self.localizer is not None:
            return self.localizer.pose()
        return self.robot.base_pose2d()

    def arm_ik(self, tip: str) -> ArmIK:
        """The model and solvers of the robot's arm from its base link to ``tip``, built on
        first use; raises what :meth:`~bt_manip.kinematics.ArmModel.from_urdf` raises when
        there is no such chain."""
        if tip not in self._arm_iks:
            desc = self.robot.description
            model = ArmModel.from_urdf(desc.urdf_path, desc.arm.base_link, tip)
            common: dict[str, Any] = {
                "position_tolerance": IK_TOLERANCE,
                "rotation_tolerance": IK_TOLERANCE,
                "time_budget": None,
                "max_restarts": IK_MAX_RESTARTS,
                "posture_weight": IK_POSTURE_WEIGHT,
            }
            self._arm_iks[tip] = ArmIK(
                model,
                IKSolver(model, IKOptions(**common)),
                IKSolver(model, IKOptions(**common, free_axis="z")),
            )
        return self._arm_iks[tip]


class Cancellable(Protocol):
    """A running robot action as :class:`RunningActions` holds it."""

    def cancel(self, reason: str) -> None: ...


@dataclass
class RunningActions:
    """The robot actions of a run that are RUNNING now, with the robot each acts on.

    A robot action adds itself when it starts and removes itself when it finishes or is
    halted (:class:`~bt_manip.behaviours.base.RobotAction`); :meth:`of_kind` finds the ones
    another node may cancel.
    """

    _actions: dict[int, tuple[Cancellable, str]] = field(default_factory=dict, repr=False)

    def started(self, action: Cancellable, robot: str) -> None:
        self._actions[id(action)] = (action, robot)

    def finished(self, action: Cancellable) -> None:
        self._actions.pop(id(action), None)

    def of_kind(self, kind: type, robot: str) -> list[Cancellable]:
        """The running actions that are instances of ``kind`` and act on ``robot`` (or on
        the world's only robot, registered as "")."""
        return [a for a, r in self._actions.values()
                if isinstance(a, kind) and (r == robot or not r)]


@dataclass
class RunContext(TreeContext):
    """A tree context with the services of a run (see the module docstring)."""

    world: World | None = None
    faults: FaultInjector | None = None
    overlay: Overlay = field(default_factory=Overlay)
    running: RunningActions = field(default_factory=RunningActions)
    localization: RunLocalization | None = None
    """The run's localisation (:mod:`bt_manip.localization.runtime`); None when off."""
    _robots: dict[str, RobotServices] = field(default_factory=dict, init=False, repr=False)

    @classmethod
    def for_world(cls, world: World, faults: FaultInjector | None = None) -> RunContext:
        """A context ticking on ``world``'s sim clock."""
        return cls(clock=world.clock, world=world, faults=faults)

    def arm_planning(self) -> dict[str, dict[str, float]]:
        """Per robot whose arm planned in this run: the plans made, the samples drawn and the
        wall time spent planning (s); empty when no arm planned."""
        out: dict[str, dict[str, float]] = {}
        for name, services in sorted(self._robots.items()):
            planner = services.arm_planner
            if planner is not None and planner.plans:
                out[name] = {"plans": planner.plans, "samples": planner.samples,
                             "wall_time_s": round(planner.wall_time, 4)}
        return out

    def robot_services(self, name: str) -> RobotServices:
        """The services of the world's robot ``name`` (KeyError when there is none)."""
        services = self._robots.get(name)
        if services is None:
            if self.world is None:
                raise KeyError(name)
            localizer = self.localization.get(name) if self.localization is not None else None
            services = RobotServices(self.world, self.world.robots[name], localizer)
            self._robots[name] = services
        return services

