"""Nav2's Cancel* nodes: CancelControl, CancelBackUp, CancelSpin, CancelWait and
CancelDriveOnHeading.

In Nav2 each cancels every goal of one action server (the controller, or a behaviour of the
behaviour server), whichever node of the tree sent it. Here the action servers are the robot
actions of the run: a Cancel node cancels every action of its kind RUNNING on its robot now
(the run lists them, :class:`~bt_manip.run.context.RunningActions`). A cancelled action leaves
the robot safe at once (the base stops) and returns SUCCESS at its next tick with result code 0,
as Nav2's action nodes do when their goal is cancelled.

(``CancelAssistedTeleop`` is not provided: bt-manip has no AssistedTeleop.)
"""

from __future__ import annotations

from typing import ClassVar

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ROBOT_PORT, ActionFailed, WorldAccess
from bt_manip.bt.node import PortError, SyncActionNode
from bt_manip.bt.ports import Accepts, Port
from bt_manip.bt.registry import registry
from bt_manip.nav2.actions import BackUp, DriveOnHeading, FollowPath, Spin, Wait

CANCEL_PORTS: dict[str, PortInformation] = {
    "robot": ROBOT_PORT,
    "server_name": PortInformation(str, False, "Action server name", ""),
    "server_timeout": Port(int, False, "Action server timeout (ms)", 20, Accepts(low=0)),
}


class _Cancel(WorldAccess, SyncActionNode):
    """Cancels the running actions of class ``CANCELS`` on the node's robot.

    - SUCCESS: every such action was cancelled (the feedback says how many; none running is
      SUCCESS too, as cancelling an idle Nav2 server is);
    - FAILURE: there is no world, or the robot cannot be named (the reason says why).
    """

    CANCELS: ClassVar[type] = object
    INPUT_PORTS: dict[str, PortInformation] = CANCEL_PORTS

    def update(self) -> Status:
        try:
            robot = self.robot_name()
            running = self.run_context.running.of_kind(self.CANCELS, robot)
        except (ActionFailed, PortError) as exc:
            self.feedback_message = str(exc)
            return Status.FAILURE
        what = self.CANCELS.__name__
        for action in running:
            action.cancel(f"{self.NODE_ID} on {robot}")
        self.feedback_message = (
            f"cancelled {len(running)} {what}" if running else f"no {what} running on {robot}")
        return Status.SUCCESS


@registry.register
class CancelControl(_Cancel):
    """Cancels the robot's running FollowPath (Nav2's controller server); statuses as
    every Cancel node (module docstring): SUCCESS, or FAILURE without a world or robot."""

    CANCELS = FollowPath


@registry.register
class CancelBackUp(_Cancel):
    """Cancels the robot's running BackUp; SUCCESS, or FAILURE without a world or robot."""

    CANCELS = BackUp


@registry.register
class CancelSpin(_Cancel):
    """Cancels the robot's running Spin; SUCCESS, or FAILURE without a world or robot."""

    CANCELS = Spin


@registry.register
class CancelWait(_Cancel):
    """Cancels the running Wait; SUCCESS, or FAILURE without a world or robot."""

    CANCELS = Wait


@registry.register
class CancelDriveOnHeading(_Cancel):
    """Cancels the robot's running DriveOnHeading; SUCCESS, or FAILURE without a world or
    robot."""

    CANCELS = DriveOnHeading
