"""Nav2's ReinitializeGlobalLocalization on bt-manip's localisation.

In Nav2 the node calls AMCL's ``reinitialize_global_localization`` service: the particles are
spread uniformly over the map's free space and the robot must move (spin) for the filter to
find it again. Here it does the same to the run's particle filter
(:mod:`bt_manip.localization.runtime`); the ports are Nav2's (``service_name``,
``server_timeout``; there is one filter per robot, so the name changes nothing).
"""

from __future__ import annotations

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import RobotAction
from bt_manip.behaviours.localization import localizer_of
from bt_manip.bt.registry import registry

__all__ = ["ReinitializeGlobalLocalization"]


@registry.register
class ReinitializeGlobalLocalization(RobotAction):
    """Spreads the robot's localisation particles uniformly over the map's free space (the
    filter forgets where it thought the robot was); the robot's belief stays where it was until
    the filter takes its next scan. Spin the robot afterwards so that it finds itself.

    - SUCCESS once the particles are spread (within the tick);
    - FAILURE when the run does not localise the robot (no ``--localize``).
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "service_name": PortInformation(str, False, "Service name",
                                        "reinitialize_global_localization"),
        "server_timeout": PortInformation(float, False, "Server timeout (ms)", 50.0),
    }

    def start(self) -> None:
        localizer_of(self).global_localization()

    def step(self) -> Status:
        return Status.SUCCESS
