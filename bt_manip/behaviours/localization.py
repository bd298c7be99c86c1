"""Nodes on a robot's localisation: IsLocalized and SetInitialPose (bt-manip's own), and the
helper every localisation node uses to find the robot's localiser.

Both act on the run's localisation (:mod:`bt_manip.localization.runtime`, on with
``--localize`` or a world's ``localization:`` section) and fail with a reason when it is off.
Nav2's ReinitializeGlobalLocalization is in :mod:`bt_manip.nav2.localization`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction, WorldAccess, WorldCondition
from bt_manip.behaviours.navigate import goal_text_problem, parse_goal
from bt_manip.bt.ports import NON_NEGATIVE, POSITIVE, Accepts, Port
from bt_manip.bt.registry import registry

if TYPE_CHECKING:
    from bt_manip.localization.runtime import Localizer

LOCALIZATION_OFF = ("the robot does not localise in this run: run with --localize (or give the "
                    "world a localization: section)")
"""The reason a localisation node fails with when localisation is off."""


def localizer_of(node: WorldAccess) -> Localizer:
    """The localiser of the robot ``node`` acts on; ActionFailed when the run does not
    localise it."""
    robot = node.robot()
    run = node.run_context.localization
    loc = run.get(node.robot_name_of(robot)) if run is not None else None
    if loc is None:
        raise ActionFailed(LOCALIZATION_OFF if run is None else
                           f"robot '{node.robot_name_of(robot)}' has no laser: it does not "
                           "localise")
    return loc


@registry.register
class IsLocalized(WorldCondition):
    """Whether the robot knows where it is: the particle filter's estimate has standard
    deviations within ``max_xy_std`` (x and y, m) and ``max_yaw_std`` (rad), and the filter
    does not say it is lost (its best cluster holds most of the weight and the scans fit the
    map as well as they did).

    - SUCCESS when both hold;
    - FAILURE otherwise, the reason giving the spread or why the filter is lost;
    - FAILURE when the run does not localise the robot (no ``--localize``).
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "max_xy_std": Port(float, False, "largest standard deviation in x and y (m)", 0.1,
                           POSITIVE),
        "max_yaw_std": Port(float, False, "largest standard deviation in yaw (rad)", 0.1,
                            POSITIVE),
    }

    def check(self) -> tuple[bool, str]:
        est = localizer_of(self).estimate
        sx, sy, syaw = est.std
        max_xy = float(self.get_input("max_xy_std"))
        max_yaw = float(self.get_input("max_yaw_std"))
        if max(sx, sy) > max_xy:
            return False, f"position spread {max(sx, sy):.3f} m exceeds max_xy_std {max_xy:g} m"
        if syaw > max_yaw:
            return False, f"heading spread {syaw:.3f} rad exceeds max_yaw_std {max_yaw:g} rad"
        if est.lost:
            return False, f"the filter is lost: {est.reason}"
        return True, ""


@registry.register
class SetInitialPose(RobotAction):
    """Tells the robot's localisation where it is (as RViz's "2D Pose Estimate" does): the
    particle filter starts again around ``pose`` with standard deviations ``xy_std`` and
    ``yaw_std``, and the robot believes it is at ``pose`` until its next scan is taken.

    - SUCCESS once the filter has started again (within the tick);
    - FAILURE when ``pose`` is neither a named pose of the world nor x;y;yaw, or the run does
      not localise the robot (no ``--localize``).
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "pose": Port(str, True, "named world pose, or x;y;yaw (m, rad; map)",
                     accepts=Accepts(check=goal_text_problem)),
        "xy_std": Port(float, False, "standard deviation in x and y (m)", 0.25, NON_NEGATIVE),
        "yaw_std": Port(float, False, "standard deviation in yaw (rad)", math.radians(15.0),
                        NON_NEGATIVE),
    }

    def start(self) -> None:
        loc = localizer_of(self)
        pose = parse_goal(self.world, self.get_input("pose"))
        xy, yaw = float(self.get_input("xy_std")), float(self.get_input("yaw_std"))
        loc.reset(pose, (xy, xy, yaw))

    def step(self) -> Status:
        return Status.SUCCESS
