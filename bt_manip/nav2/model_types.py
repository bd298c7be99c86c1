"""The C++ type names Nav2 gives its nodes' ports, for the TreeNodesModel.

bt-manip's Nav2 nodes hold Python values (a :class:`~bt_manip.nav2.path.Nav2Path`, a pose
tuple, an int); Groot2 shows the type each port declares in the model, and Nav2's model
declares ROS message types. :func:`apply_model_types` gives every registered Nav2 node the
names below (as ``MODEL_TYPE_NAMES``), so ``bt-manip nodes --groot`` shows the ports as Nav2
does. Only the model export reads these names: the blackboard keeps typing entries by the
Python types.
"""

from __future__ import annotations

from bt_manip.bt.registry import NodeRegistry

PATH = "nav_msgs::msg::Path"
POSE = "geometry_msgs::msg::PoseStamped"
POSES = "std::vector<geometry_msgs::msg::PoseStamped>"
ERROR_CODE = "uint16_t"
MILLISECONDS = "std::chrono::milliseconds"

PORT_TYPES: dict[str, str] = {
    "path": PATH,
    "input_path": PATH,
    "output_path": PATH,
    "unsmoothed_path": PATH,
    "smoothed_path": PATH,
    "goal": POSE,
    "start": POSE,
    "pose": POSE,
    "input_goal": POSE,
    "output_goal": POSE,
    "goals": POSES,
    "input_goals": POSES,
    "output_goals": POSES,
    "error_code_id": ERROR_CODE,
    "error_code": ERROR_CODE,
    "error_codes_to_check": "std::vector<int>",
    "server_timeout": MILLISECONDS,
    "input_path1": PATH,
    "input_path2": PATH,
    "route_path": PATH,
    "ref_pose": POSE,
    "target_pose": POSE,
    "current_pose": POSE,
    "goal_pose": POSE,
    "collision_poses": POSES,
    "route": "nav2_msgs::msg::Route",
    "tracking_feedback": "nav2_msgs::msg::TrackingFeedback",
    "input_waypoint_statuses": "std::vector<nav2_msgs::msg::WaypointStatus>",
    "output_waypoint_statuses": "std::vector<nav2_msgs::msg::WaypointStatus>",
    "planning_time": "builtin_interfaces::msg::Duration",
}
"""Nav2's type of a port, by the port's name (the same name has the same type in every node
of Nav2's library)."""

NODE_PORT_TYPES: dict[str, dict[str, str]] = {
    "IsPathValid": {"max_cost": "unsigned int"},
    "ValidatePath": {"max_cost": "unsigned int"},
    "ComputeRoute": {"start_id": "unsigned int", "goal_id": "unsigned int"},
}
"""Types that only one node gives a port."""

NAV2_MODULE = "bt_manip.nav2"


def model_types_of(node_id: str, ports: list[str]) -> dict[str, str]:
    """Nav2's type names of a node's ``ports`` (those Nav2 names; others are left out)."""
    names = {p: PORT_TYPES[p] for p in ports if p in PORT_TYPES}
    names.update({p: t for p, t in NODE_PORT_TYPES.get(node_id, {}).items() if p in ports})
    return names


def apply_model_types(reg: NodeRegistry) -> None:
    """Give each Nav2 node class of ``reg`` its ``MODEL_TYPE_NAMES``."""
    for cls in reg.classes():
        if cls.__module__.startswith(NAV2_MODULE + "."):
            ports = [*cls.INPUT_PORTS, *cls.OUTPUT_PORTS]
            cls.MODEL_TYPE_NAMES = model_types_of(cls.NODE_ID, ports)
