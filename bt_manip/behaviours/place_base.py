"""PlanBaseForPlace: where to park a mobile manipulator so that its arm can place what it holds.

The node reads its ports, checks that the robot holds the object, runs the search of
:mod:`bt_manip.manipulation.place_search` (its candidates and checks are described there) and
writes the base pose it found; a search that finds none, or cannot start, is its FAILURE reason.
"""

from __future__ import annotations

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction, skid_steer_refusal
from bt_manip.behaviours.base_placement import BASE_POSE, CLEARANCE, STAGING_POSE, pose_text
from bt_manip.behaviours.navigate import synced_navigator
from bt_manip.behaviours.place import (
    APPROACH,
    DEFAULT_GAP,
    OBJECT,
    TARGET,
    held_body,
    read_target,
)
from bt_manip.bt import registry
from bt_manip.manipulation.base_search import PlacementOptions
from bt_manip.manipulation.place_search import PLACE_STAGING, plan_place_base


@registry.register
class PlanBaseForPlace(RobotAction):
    """Finds a base pose from which the arm places the held ``object`` at ``target``
    (``x;y;z;yaw`` of its centre), as the Place node does it: from ``approach`` m above, straight
    down (see :mod:`bt_manip.manipulation.place_search`).

    - SUCCESS with ``base_pose`` (``x;y;yaw``, for ``Navigate goal="{base_pose}"``) and
      ``staging_pose`` (the pose to line up at first, ``staging`` m behind, facing the same
      way) set;
    - FAILURE when the robot does not hold the object, the target is not ``x;y;z;yaw``, or no
      sampled pose passes every check: the reason starts "no base pose from which the arm
      places OBJECT" and counts what each check rejected.
    It does its work in the tick it starts (bounded), so it is never RUNNING and halting has
    nothing to undo.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "object": OBJECT,
        "target": TARGET,
        "approach": APPROACH,
        "clearance": CLEARANCE,
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "base_pose": BASE_POSE,
        "staging_pose": STAGING_POSE,
    }

    def start(self) -> None:
        robot = self.robot()
        refusal = skid_steer_refusal(robot, "PlanBaseForPlace")
        if refusal is not None:
            raise ActionFailed(refusal)
        name = self.get_input("object")
        options = PlacementOptions(
            approach=float(self.get_input("approach")),
            clearance=float(self.get_input("clearance")),
            arm_state="",
            staging=PLACE_STAGING,
        )
        target = read_target(self)
        body = held_body(self, name)
        nav = synced_navigator(self, robot)
        services = self.run_context.robot_services(self.robot_name_of(robot))
        placement = plan_place_base(nav, services, body, name, target, options, DEFAULT_GAP)
        if not placement.ok:
            raise ActionFailed(
                f"no base pose from which the arm places {name}: {placement.reason}"
            )
        assert placement.base_pose is not None
        self.set_output("base_pose", pose_text(placement.base_pose))
        self.set_output("staging_pose", pose_text(placement.staging_pose or ()))
        if placement.grasp is not None:
            self.overlay.show_frame("ik_target", placement.grasp)

    def step(self) -> Status:
        return Status.SUCCESS
