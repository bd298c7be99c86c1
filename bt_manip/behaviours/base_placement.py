"""PlanBaseForGrasp: where to park a mobile manipulator so that its arm can take an object.

The node reads its ports, runs the search of :mod:`bt_manip.manipulation.base_search` (its
samples, checks, score and budgets are described there) on the robot's navigator and arm IK, and
writes the base pose it found; a search that finds none, or cannot start, is its FAILURE reason.
"""

from __future__ import annotations

from typing import Any

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction, skid_steer_refusal
from bt_manip.behaviours.navigate import synced_navigator
from bt_manip.bt import registry
from bt_manip.bt.ports import Accepts, Port
from bt_manip.geometry import quat_from_matrix
from bt_manip.manipulation.base_search import PlacementOptions, plan_base
from bt_manip.manipulation.grasps import GRASPS


def pose_text(values: Any) -> str:
    return ";".join(f"{float(v):.4f}" for v in values)


CLEARANCE = Port(
    float, False, "footprint clearance from obstacles (m)", PlacementOptions.clearance,
    Accepts(0.0, 0.5),
)
BASE_POSE = PortInformation(str, False, "base pose x;y;yaw for Navigate goal")
STAGING_POSE = PortInformation(
    str, False, "pose x;y;yaw to line up at before driving straight to base_pose"
)
"""Ports the base planners (PlanBaseForGrasp, PlanBaseForPlace) share."""


@registry.register
class PlanBaseForGrasp(RobotAction):
    """Finds a base pose from which the arm takes ``object`` with grasp ``grasp`` (``top``).

    The object's pose is the one the robot perceives (ground truth plus any ``--inject
    pose_noise``); base poses are sampled around it, checked against the navigator's occupancy
    grid, the arm's IK (pre-grasp point and straight approach) and a path from where the robot
    is, and the best by score is taken (see :mod:`bt_manip.manipulation.base_search`).

    - SUCCESS with ``base_pose`` set to ``x;y;yaw`` (what ``Navigate goal="{base_pose}"``
      reads), ``staging_pose`` to the pose to line up at first (``staging`` m behind, facing
      the same way: drive there, then straight in to ``base_pose``) and ``grasp_pose`` to the
      grasp frame ``x;y;z;qx;qy;qz;qw`` (world);
    - FAILURE when the object cannot be grasped so (not a box, too wide for the fingers) or no
      sampled pose passes every check: the reason starts "no base pose from which the arm
      reaches OBJECT" and counts what each check rejected.
    It does its work in the tick it starts (bounded, see the module), so it is never RUNNING
    and halting has nothing to undo.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "object": PortInformation(str, True, "name of a movable object of the world"),
        "grasp": Port(str, False, "grasp of the object: top", "top", Accepts(choices=GRASPS)),
        "approach": Port(
            float, False, "pre-grasp distance back along the approach axis (m)",
            PlacementOptions.approach, Accepts(0.0, 0.3),
        ),
        "clearance": CLEARANCE,
        "arm_state": PortInformation(
            str, False, "named arm state the reach starts from (empty: the posture now)",
            PlacementOptions.arm_state,
        ),
        "staging": Port(
            float, False, "how far behind base_pose to line up (m)", PlacementOptions.staging,
            Accepts(0.2, 2.0),
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "base_pose": BASE_POSE,
        "staging_pose": STAGING_POSE,
        "grasp_pose": PortInformation(str, False, "grasp frame x;y;z;qx;qy;qz;qw (world)"),
    }

    def start(self) -> None:
        robot = self.robot()
        refusal = skid_steer_refusal(robot, "PlanBaseForGrasp")
        if refusal is not None:
            raise ActionFailed(refusal)
        name = self.get_input("object")
        options = PlacementOptions(
            approach=float(self.get_input("approach")),
            clearance=float(self.get_input("clearance")),
            arm_state=self.get_input("arm_state"),
            staging=float(self.get_input("staging")),
        )
        nav = synced_navigator(self, robot)
        services = self.run_context.robot_services(self.robot_name_of(robot))
        placement = plan_base(nav, services, self.faults(), name, self.get_input("grasp"), options)
        if not placement.ok:
            raise ActionFailed(
                f"no base pose from which the arm reaches {name}: {placement.reason}"
            )
        assert placement.base_pose is not None and placement.grasp is not None
        # worked out from the object as the robot sees it: a pose relative to the object, put
        # in the map frame of the robot's belief (unchanged without localisation)
        self.set_output("base_pose", pose_text(self.seen_in_map(placement.base_pose, robot)))
        self.set_output("staging_pose",
                        pose_text(self.seen_in_map(placement.staging_pose or (), robot)))
        grasp = placement.grasp
        self.set_output(
            "grasp_pose", pose_text([*grasp[:3, 3], *quat_from_matrix(grasp[:3, :3])])
        )
        self.overlay.show_frame("ik_target", grasp)

    def step(self) -> Status:
        return Status.SUCCESS
