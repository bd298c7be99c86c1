"""Fasten: fix a placed object to the structure it stands on or against, as a fastener would.

Only an object within its placement tolerance of its target is fastened (the true pose is
checked, not what the robot believes): a fastener does not pull a misplaced panel into place.
The object is fixed by a fixed joint (:mod:`bt_manip.sim.fasteners`) to the nearest wall or
piece of furniture within ``max_gap``, else to the floor; it keeps the pose it has. The tree
then opens the gripper and detaches: the object stays where it was fastened.
"""

from __future__ import annotations

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction
from bt_manip.behaviours.place import (
    ANGLE_TOLERANCE,
    POSITION_TOLERANCE,
    TARGET,
    read_target,
    tolerance_problem,
)
from bt_manip.bt import registry
from bt_manip.bt.ports import Accepts, Port
from bt_manip.manipulation.perception import true_pose
from bt_manip.manipulation.placing import deviation
from bt_manip.sim.fasteners import fasten, fastenings, structures_near

DEFAULT_MAX_GAP = 0.01
"""Farthest (m) a structure may be from the object and still be fastened to."""


@registry.register
class Fasten(RobotAction):
    """Fixes ``object`` to the structure it stands on or against, if it is at ``target``.

    - SUCCESS when the fixed joint is made; ``fastened_to`` names the structure (a wall or
      piece of furniture within ``max_gap``, else the floor);
    - FAILURE, with the reason, when the object's true pose is farther than
      ``position_tolerance`` (m) or ``angle_tolerance`` (deg) from ``target``, no structure
      is within ``max_gap``, or the object is already fastened.
    It does its work in the tick it starts, so it is never RUNNING and halting has nothing to
    undo.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "object": PortInformation(str, True, "name of a movable object of the world"),
        "target": TARGET,
        "position_tolerance": POSITION_TOLERANCE,
        "angle_tolerance": ANGLE_TOLERANCE,
        "max_gap": Port(
            float, False, "farthest a structure may be from the object (m)", DEFAULT_MAX_GAP,
            Accepts(0.0, 0.05),
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "fastened_to": PortInformation(str, False, "the structure the object is fixed to"),
    }

    def start(self) -> None:
        name = self.get_input("object")
        body = self.object_body(name)
        world = self.world
        done = fastenings(world)
        if name in done:
            raise ActionFailed(f"'{name}' is already fastened to '{done[name]}'")
        target = read_target(self)
        dev = deviation(true_pose(world, body), target)
        problem = tolerance_problem(self, name, dev, target)
        if problem is not None:
            raise ActionFailed(f"{problem}: not fastened")
        max_gap = float(self.get_input("max_gap"))
        near = structures_near(world, body, max_gap)
        if not near:
            raise ActionFailed(
                f"nothing to fasten '{name}' to: no wall, furniture or floor within "
                f"{max_gap * 100:.1f} cm"
            )
        fasten(world, body, near[0])
        self.set_output("fastened_to", near[0].name)
        self.feedback_message = f"'{name}' fastened to '{near[0].name}'"

    def step(self) -> Status:
        return Status.SUCCESS
