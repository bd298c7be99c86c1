"""DriveStraight: drive the base straight ahead (or back) onto a pose it already faces.

The last stretch to a place where the robot sets something down: lined up behind the pose (a
staging pose, see PlanBaseForPlace), the robot drives forward along the line to it, steering
only gently back onto that line, and stops there. No path is planned and the robot does not
turn on the spot, so a long load held across it does not sweep round near a wall as it would
while a path follower corrects its heading at the goal.
"""

from __future__ import annotations

import math

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction, skid_steer_refusal
from bt_manip.behaviours.navigate import base_contacts, parse_goal
from bt_manip.bt import registry
from bt_manip.bt.ports import POSITIVE, Accepts, Port

DRIVE_OVER = 0.02
"""Bodies lower than this (m) are driven over: the navigator maps nothing lower either."""
MAX_START_TURN = 0.3
"""Largest angle (rad) between the robot's heading and the goal's at the start."""
STEER_GAIN = 1.5
"""Turn rate (rad/s) per radian of heading error."""
MAX_TURN_RATE = 0.3
"""Largest turn rate (rad/s) while driving straight."""
SLOW_DOWN = 0.15
"""Within this distance (m) of the goal the speed falls off linearly (to a quarter)."""


def wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


@registry.register
class DriveStraight(RobotAction):
    """Drives forward along the line to ``goal`` (``x;y;yaw`` or a named pose), which the
    robot must already face (within 0.3 rad), and stops on it; with ``direction="backward"``
    it backs along the line onto a goal behind it (backing out the way it came in).

    - RUNNING while driving;
    - SUCCESS when the robot has reached the goal along its heading, within ``xy_tolerance``
      (m) of it and ``yaw_tolerance`` (rad) of its heading;
    - FAILURE, with the reason, when the goal is behind the robot or not faced, the robot or
      what it carries touches anything but the floor and bodies lower than 2 cm (it stops
      there), it stops off the goal
      by more than the tolerances, or ``timeout`` s pass.
    Halted: the base is braked where it is.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "goal": PortInformation(str, True, "pose x;y;yaw or a named pose of the world"),
        "speed": Port(float, False, "driving speed (m/s)", 0.15, Accepts(0.0, 1.0, low_open=True)),
        "xy_tolerance": Port(float, False, "distance allowed from the goal (m)", 0.03, POSITIVE),
        "yaw_tolerance": Port(float, False, "heading error allowed (rad)", 0.05, POSITIVE),
        "timeout": Port(float, False, "sim seconds allowed", 30.0, POSITIVE),
        "direction": Port(
            str, False, "forward, or backward onto a goal behind the robot", "forward",
            Accepts(choices=("forward", "backward")),
        ),
    }

    def start(self) -> None:
        robot = self.robot()
        refusal = skid_steer_refusal(robot, "DriveStraight")
        if refusal is not None:
            raise ActionFailed(refusal)
        self.goal = parse_goal(self.world, self.get_input("goal"))
        self.back = self.get_input("direction") == "backward"
        x, y, yaw = robot.base_pose2d()
        gx, gy, gyaw = self.goal
        turn = abs(wrap(gyaw - yaw))
        if turn > MAX_START_TURN:
            raise ActionFailed(
                f"the robot faces {math.degrees(turn):.0f} deg away from the goal's heading "
                f"(at most {math.degrees(MAX_START_TURN):.0f}): line it up first"
            )
        way = gyaw + (math.pi if self.back else 0.0)  # the direction of travel
        ahead = (gx - x) * math.cos(way) + (gy - y) * math.sin(way)
        if ahead < -float(self.get_input("xy_tolerance")):
            where = "ahead of" if self.back else "behind"
            raise ActionFailed(f"the goal is {-ahead:.2f} m {where} the robot")
        self.touching = self._contacts()

    def _contacts(self) -> set[str]:
        """Bodies the robot or its load touch now, except the floor and what is low enough to
        drive over (the rails of an empty stand)."""
        return base_contacts(self.world, self.robot(), self.robot_name(), DRIVE_OVER)

    def step(self) -> Status:
        robot = self.robot()
        new = self._contacts() - self.touching
        if new:
            robot.stop_base()
            raise ActionFailed("driving in, touched " + ", ".join(f"'{n}'" for n in sorted(new)))
        x, y, yaw = robot.base_pose2d()
        gx, gy, gyaw = self.goal
        turn = math.pi if self.back else 0.0  # headings of travel: the robot's and the goal's
        c, s = math.cos(gyaw + turn), math.sin(gyaw + turn)
        ahead = (gx - x) * c + (gy - y) * s
        side = -(gx - x) * s + (gy - y) * c  # the goal line is to the left when positive
        if ahead <= 0.002:
            robot.stop_base()
            off = math.hypot(gx - x, gy - y)
            turn = abs(wrap(gyaw - yaw))
            if off > float(self.get_input("xy_tolerance")) or turn > float(
                self.get_input("yaw_tolerance")
            ):
                raise ActionFailed(
                    f"stopped {off * 100:.1f} cm and {math.degrees(turn):.1f} deg off the goal"
                )
            return Status.SUCCESS
        if self.elapsed() > float(self.get_input("timeout")):
            robot.stop_base()
            raise ActionFailed(f"not at the goal after {float(self.get_input('timeout')):g} s: "
                               f"{ahead:.2f} m to go")
        # head for a point on the goal line a little ahead; over the last stretch, for the
        # goal's heading only
        look = max(ahead, 0.3)
        want = gyaw + turn + (math.atan2(side, look) if ahead > SLOW_DOWN else 0.0)
        rate = max(-MAX_TURN_RATE, min(MAX_TURN_RATE, STEER_GAIN * wrap(want - yaw - turn)))
        speed = float(self.get_input("speed"))
        if ahead < SLOW_DOWN:
            speed *= 0.25 + 0.75 * ahead / SLOW_DOWN
        robot.set_base_twist(-speed if self.back else speed, rate)
        return Status.RUNNING
