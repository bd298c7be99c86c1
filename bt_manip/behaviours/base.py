"""What every robot behaviour shares: finding its world and robot, failing with a reason, and
leaving the robot safe when halted.

A robot behaviour is an :class:`~bt_manip.bt.ActionNode` whose ``robot`` port names a robot of
the world (empty = the world's only robot). It never raises through the tree: anything that
prevents the action (no world, unknown robot or object, unreachable target, time-out, a port
value read from the blackboard that the port cannot take) makes it return FAILURE with the
reason in ``feedback_message``, which the console and the run report show.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, cast

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.bt import ActionNode, ConditionNode, PortError, TreeContext
from bt_manip.kinematics.reasons import SOLVER_KNOBS
from bt_manip.localization.frames import compose, inverse
from bt_manip.manipulation.arm_planner import ArmPlanner
from bt_manip.manipulation.errors import ManipulationError
from bt_manip.manipulation.grasps import grasped_object
from bt_manip.manipulation.perception import PerceptionError, movable_body, perceived_pose
from bt_manip.overlay import Overlay
from bt_manip.run.context import RobotServices, RunContext
from bt_manip.run.faults import FaultInjector, PendingSlip, plan_slip, slip_out

if TYPE_CHECKING:
    from bt_manip.sim.robot import Robot
    from bt_manip.sim.world import World

ROBOT_PORT = PortInformation(
    data_type=str,
    required=False,
    default_value="",
    description="robot name in the world (empty: the only robot)",
)


class ActionFailed(Exception):
    """Raised inside a behaviour to end it with FAILURE and this reason."""


FAILS = (ActionFailed, PortError, ManipulationError)
"""What ends a behaviour with FAILURE, its message the reason: the node's own failures, a port
value it cannot take, and what the manipulation helpers it calls cannot do."""

TREE_IK_KNOBS = (
    "try another target (an offset, a height or an orientation the node's ports set), or the "
    "base moved closer (Navigate, PlanBaseForGrasp)"
)
"""What a tree can change when the IK solver gives up inside a node that does not name its own
ports instead (the solver's own advice names options a tree cannot set)."""


def failure_reason(exc: BaseException) -> str:
    """The reason a node reports for ``exc``: its message, with the IK solver's advice (options
    of the Python API) replaced by what a tree can change."""
    text = str(exc)
    return text.replace(SOLVER_KNOBS, TREE_IK_KNOBS) if SOLVER_KNOBS in text else text


def skid_steer_refusal(robot: Robot, node_id: str) -> str | None:
    """Why ``node_id`` cannot drive ``robot`` (a :class:`bt_manip.sim.robot.Robot`), or None when
    its base is a skid-steer base, the only kind the node drives."""
    kind = robot.description.base.type
    if kind == "skid_steer":
        return None
    if kind == "fixed":
        return f"{robot.description.name} has no mobile base"
    return (f"{robot.description.name} has a {kind} base; {node_id} drives skid-steer bases only "
            "(Navigate and Reverse drive every mobile base)")


class _Node(Protocol):
    """What :class:`WorldAccess` uses of the node class it is mixed into (a ``BtNode``)."""

    INPUT_PORTS: ClassVar[dict[str, PortInformation]]
    context: TreeContext

    def get_input(self, port_name: str, default: Any = ...) -> Any: ...


class WorldAccess:
    """Mixin: the world and robot a node acts on, resolved from its ports and context."""

    NEEDS_WORLD: ClassVar[bool] = True
    WORLD_NAMES: ClassVar[dict[str, str]] = {
        "robot": "robot", "object": "body", "inside": "body", "region": "body", "goal": "pose",
    }
    """The ports of these names, where a node has them, name things of the world (see
    :attr:`bt_manip.bt.node.BtNode.WORLD_NAMES`)."""

    feedback_message: str

    @property
    def world(self) -> World:
        world: World | None = cast(_Node, self).context.world
        if world is None:
            raise ActionFailed("this node needs a world (run with --world)")
        return world

    @property
    def run_context(self) -> RunContext:
        """The run's services; a tree built in Python is given them with
        ``RunContext.for_world(world)``."""
        context = cast(_Node, self).context
        if not isinstance(context, RunContext):
            _ = self.world  # without a world, that is the problem to report
            raise ActionFailed(
                "this node needs the services of a run: give the tree "
                "bt_manip.run.context.RunContext.for_world(world) as its context"
            )
        return context

    def services(self) -> RobotServices:
        """The navigator and arm IK of the robot this node acts on."""
        robot = self.robot()
        return self.run_context.robot_services(self.robot_name_of(robot))

    def arm_planner(self) -> ArmPlanner:
        """The arm planner (planning scene and plans) of the robot this node acts on, made on
        first use and kept with the robot's services for the run."""
        services = self.services()
        if services.arm_planner is None:
            robot = self.robot()
            services.arm_planner = ArmPlanner(self.world, robot, self.robot_name_of(robot))
        planner: ArmPlanner = services.arm_planner
        return planner

    @property
    def overlay(self) -> Overlay:
        """What this run's viewers draw over the world (a throwaway one outside a run)."""
        context = cast(_Node, self).context
        return context.overlay if isinstance(context, RunContext) else Overlay()

    def robot(self) -> Robot:
        """The robot named by the ``robot`` port, or the only robot of the world."""
        robots = self.world.robots
        node = cast(_Node, self)
        name = node.get_input("robot") if "robot" in node.INPUT_PORTS else ""
        if not name:
            if len(robots) != 1:
                raise ActionFailed(
                    f'the world has {len(robots)} robots; say which with robot="..." '
                    f"({', '.join(robots) or 'none'})"
                )
            return next(iter(robots.values()))
        if name not in robots:
            raise ActionFailed(f"no robot named '{name}'; robots: {', '.join(robots) or 'none'}")
        return robots[name]

    def robot_name(self) -> str:
        return self.robot_name_of(self.robot())

    def robot_name_of(self, robot: Robot) -> str:
        robots: dict[str, Robot] = self.world.robots
        for name, r in robots.items():
            if r is robot:
                return name
        return ""

    def object_body(self, name: str) -> int:
        """PyBullet id of a movable object of the world."""
        try:
            return movable_body(self.world, name)
        except PerceptionError as exc:
            raise ActionFailed(str(exc)) from None

    def faults(self) -> FaultInjector | None:
        """The run's fault injector, when faults are injected."""
        context = cast(_Node, self).context
        return context.faults if isinstance(context, RunContext) else None

    def believed_pose(self, robot: Robot | None = None) -> tuple[float, float, float]:
        """The pose (x, y, yaw; map frame) the robot (default: this node's) believes its base
        has: the localisation's estimate when the run localises, else the ground truth (see
        :meth:`~bt_manip.run.context.RobotServices.believed_pose`). Navigation decides on this;
        physics, the arm and reports keep the ground truth."""
        robot = robot if robot is not None else self.robot()
        context = cast(_Node, self).context
        if not isinstance(context, RunContext) or context.localization is None:
            return robot.base_pose2d()
        return context.robot_services(self.robot_name_of(robot)).believed_pose()

    def odom_pose(self, robot: Robot | None = None) -> tuple[float, float, float]:
        """The robot's pose in its odometry frame when the run localises it (continuous: it
        never jumps when the filter corrects itself), else the ground truth. Motions measured
        from where they started (Spin, BackUp, Reverse) use this, as Nav2's behaviour server
        works in the ``odom`` frame."""
        robot = robot if robot is not None else self.robot()
        context = cast(_Node, self).context
        if not isinstance(context, RunContext) or context.localization is None:
            return robot.base_pose2d()
        loc = context.robot_services(self.robot_name_of(robot)).localizer
        if loc is None:
            return robot.base_pose2d()
        o = loc.odometry.reading()
        return (o.x, o.y, o.yaw)

    def map_to_world(self, target: Sequence[float],
                     robot: Robot | None = None) -> tuple[float, float, float]:
        """Where a map-frame target (x, y, yaw) lies in the world for the robot's belief:
        ``true_base * inverse(believed_base) * target`` (unchanged without localisation). A
        node that acts on a map-frame target with the arm (Place) aims there: the target
        carries the localisation's error, as it does for a base driven to it on the
        estimate."""
        x, y, yaw = (float(v) for v in target[:3])
        robot = robot if robot is not None else self.robot()
        believed = self.believed_pose(robot)
        truth = robot.base_pose2d()
        if believed == truth:
            return (x, y, yaw)
        return compose(compose(truth, inverse(believed)), (x, y, yaw))

    def seen_in_map(self, pose: Sequence[float], robot: Robot | None = None) -> list[float]:
        """A world pose (x, y, yaw, ...) worked out from what the robot perceives around it (an
        object, as a camera sees it relative to the robot), in the map frame of the robot's
        belief: ``believed_base * inverse(true_base) * pose``, so that driving to it on the
        estimate ends where the pose is relative to the object. Unchanged without
        localisation; values after the yaw are kept."""
        values = [float(v) for v in pose]
        if len(values) < 3:
            return values
        robot = robot if robot is not None else self.robot()
        believed = self.believed_pose(robot)
        truth = robot.base_pose2d()
        if believed == truth:
            return values
        x, y, yaw = compose(compose(believed, inverse(truth)), (values[0], values[1], values[2]))
        return [x, y, yaw, *values[3:]]

    def perceived_pose(self, name: str) -> np.ndarray:
        """The pose (4x4) at which the robot sees the movable object ``name``, for planning:
        the ground truth plus the episode's ``pose_noise`` offset of that object (see
        :func:`bt_manip.manipulation.perception.perceived_pose`)."""
        self.object_body(name)
        return perceived_pose(self.world, self.faults(), name)


class RobotAction(WorldAccess, ActionNode):
    """An action on a robot. Subclasses implement :meth:`start` and :meth:`step`.

    - ``start()`` runs when the node starts; raise :class:`ActionFailed` to fail at once.
    - ``step()`` runs every tick and returns SUCCESS, FAILURE or RUNNING (it may raise
      :class:`ActionFailed`).
    - When halted while RUNNING, the robot is left safe (base braked, arm holding) and
      :meth:`on_halt` runs.
    - While RUNNING in a run, it is listed in the run's ``running`` actions, so that another
      node may :meth:`cancel` it (Nav2's Cancel* nodes): the robot is left safe at once and
      the action returns SUCCESS at its next tick, as Nav2's actions do when their goal is
      cancelled.
    """

    INPUT_PORTS: dict[str, PortInformation] = {"robot": ROBOT_PORT}
    CARRIES: ClassVar[bool] = False
    """Moves what the robot holds: a ``slip`` fault may make it let go on the way."""

    def initialise(self) -> None:
        self.feedback_message = ""
        self._start_error: str | None = None
        self._slip: PendingSlip | None = None
        self._cancelled: str | None = None
        self.started_at = self.now()
        try:
            self.start()
            if self.CARRIES:
                self._draw_slip()
        except FAILS as exc:
            self._start_error = failure_reason(exc)
        if self._start_error is None:
            self._list_running()

    def _list_running(self) -> None:
        context = self.context
        if not isinstance(context, RunContext) or context.world is None:
            return
        try:
            robot = self.robot_name()
        except (ActionFailed, PortError):
            robot = ""
        context.running.started(self, robot)

    def _unlist_running(self) -> None:
        context = self.context
        if isinstance(context, RunContext):
            context.running.finished(self)

    def cancel(self, reason: str) -> None:
        """Cancel the running action (another node asked): leave the robot safe now; the
        action returns SUCCESS at its next tick, with ``reason`` as its feedback."""
        self._cancelled = reason
        self._make_safe()
        self._unlist_running()

    def _draw_slip(self) -> None:
        """Whether a ``slip`` fault makes what the robot carries slip out during this move."""
        faults = self.faults()
        if faults is None or not faults.specs:
            return
        robot = self.robot()
        held = [a.object_name for a in self.world.attachments.held_by(self.robot_name())]
        held += [grasped_object(self.world, robot)] if not held else []
        held = [h for h in held if h]
        if held:
            self._slip = plan_slip(faults, held[0], self.started_at)

    def update(self) -> Status:
        if self._start_error is not None:
            self.feedback_message = self._start_error
            return Status.FAILURE
        if getattr(self, "_cancelled", None) is not None:
            self.feedback_message = f"cancelled: {self._cancelled}"
            return Status.SUCCESS
        try:
            if self._slip is not None and self.now() >= self._slip.at:
                slip, self._slip = self._slip, None
                slip_out(self.world, self.robot(), slip)
            return self.step()
        except FAILS as exc:
            self.feedback_message = failure_reason(exc)
            self._make_safe()
            return Status.FAILURE

    def terminate(self, new_status: Status) -> None:
        self._unlist_running()
        if new_status == Status.INVALID:
            self._make_safe()
            self.on_halt()

    def _make_safe(self) -> None:
        try:
            robot = self.robot()
        except ActionFailed:
            return
        robot.halt()

    def elapsed(self) -> float:
        """Sim time since the node started."""
        return self.now() - self.started_at

    # -- for subclasses --------------------------------------------------------------------
    def start(self) -> None:
        """Prepare the action (read ports, plan); raise ActionFailed to fail."""

    def step(self) -> Status:
        """One tick of the action."""
        raise NotImplementedError

    def on_halt(self) -> None:
        """Extra clean-up when halted."""


class WorldCondition(WorldAccess, ConditionNode):
    """A condition on the world: :meth:`check` returns (ok, reason when not ok)."""

    def update(self) -> Status:
        try:
            ok, reason = self.check()
        except FAILS as exc:
            ok, reason = False, failure_reason(exc)
        self.feedback_message = "" if ok else reason
        return Status.SUCCESS if ok else Status.FAILURE

    def check(self) -> tuple[bool, str]:
        raise NotImplementedError
