"""Helpers of the kinematics tests: a synthetic mobile manipulator and reference poses."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

from bt_manip.kinematics import ArmModel
from bt_manip.sim.assets import REPO_ROOT

SAWYER_URDF = REPO_ROOT / "robots" / "sawyer.urdf"

# A wheeled base with a lift, a 7-joint arm (one unaligned axis, one continuous joint, one
# prismatic joint) and a two-finger gripper: wheels, lift and fingers are outside the chain.
_LINK = '<link name="{0}"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" ' \
    'iyy="0.01" iyz="0" izz="0.01"/></inertial></link>'
_JOINTS = [
    # name, type, parent, child, xyz, rpy, axis, limits
    ("chassis_mount", "fixed", "base_footprint", "chassis", "0 0 0.15", "0 0 0", None, None),
    ("wheel_left", "continuous", "chassis", "wheel_l", "0 0.25 -0.05", "-1.5708 0 0", "0 0 1",
     None),
    ("wheel_right", "continuous", "chassis", "wheel_r", "0 -0.25 -0.05", "-1.5708 0 0", "0 0 1",
     None),
    ("lift", "prismatic", "chassis", "lift_link", "0.1 0 0.2", "0 0 0", "0 0 1", (0.0, 0.4)),
    ("arm_mount", "fixed", "lift_link", "arm_base", "0.05 0 0.1", "0 0 0.3", None, None),
    ("a1", "revolute", "arm_base", "l1", "0 0 0.1", "0 0 0", "0 0 1", (-3.0, 3.0)),
    ("a2", "revolute", "l1", "l2", "0 0.05 0.1", "1.5708 0 0", "0 0 1", (-2.0, 2.0)),
    ("a3", "revolute", "l2", "l3", "0 0.3 0", "-1.5708 0 0", "0 0.6 0.8", (-2.8, 2.8)),
    ("a4", "prismatic", "l3", "l4", "0 0 0.1", "0 0 0", "0 0 1", (0.0, 0.15)),
    ("a5", "revolute", "l4", "l5", "0.02 0 0.25", "1.5708 0 0", "0 0 1", (-2.5, 2.5)),
    ("a6", "continuous", "l5", "l6", "0 -0.2 0", "-1.5708 0 0", "0 0 1", None),
    ("a7", "revolute", "l6", "l7", "0 0 0.08", "1.5708 0 0", "0 0 -1", (-2.9, 2.9)),
    ("tool_mount", "fixed", "l7", "tool", "0 0 0.06", "0 0 1.5708", None, None),
    ("finger_left", "prismatic", "tool", "finger_l", "0 0.02 0.03", "0 0 0", "0 1 0", (0, 0.04)),
    ("finger_right", "prismatic", "tool", "finger_r", "0 -0.02 0.03", "0 0 0", "0 -1 0",
     (0, 0.04)),
]
COMPOSITE_CHAIN = ["a1", "a2", "a3", "a4", "a5", "a6", "a7"]


def composite_urdf_text() -> str:
    links = {"base_footprint"}
    parts = ['<?xml version="1.0"?>', '<robot name="composite">']
    for name, kind, parent, child, xyz, rpy, axis, limits in _JOINTS:
        links.update((parent, child))
        body = (
            f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{xyz}" rpy="{rpy}"/>'
        )
        if axis is not None:
            body += f'<axis xyz="{axis}"/>'
        if limits is not None:
            body += f'<limit lower="{limits[0]}" upper="{limits[1]}" effort="10" velocity="1"/>'
        parts.append(body + "</joint>")
    parts.extend(_LINK.format(link) for link in sorted(links))
    parts.append("</robot>")
    return "\n".join(parts)


def reference_pose(urdf: Path, base: str, tip: str, q_named: dict[str, float]) -> np.ndarray:
    """Tip in base computed on the whole robot with Pinocchio, independently of ArmModel.

    ``q_named`` sets joints by name (continuous joints by angle); others stay neutral.
    """
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    q = pin.neutral(model)
    for name, value in q_named.items():
        jm = model.joints[model.getJointId(name)]
        if jm.nq == 2:
            q[jm.idx_q : jm.idx_q + 2] = [np.cos(value), np.sin(value)]
        else:
            q[jm.idx_q] = value
    pin.framesForwardKinematics(model, data, q)
    base_pose = data.oMf[model.getFrameId(base, pin.FrameType.BODY)]
    tip_pose = data.oMf[model.getFrameId(tip, pin.FrameType.BODY)]
    return (base_pose.inverse() * tip_pose).homogeneous


def pose_errors(arm: ArmModel, q: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    """Largest per-axis position error (m) and rotation-vector error (rad), via Pinocchio."""
    pose = arm.fk(q)
    dp = float(np.abs(target[:3, 3] - pose[:3, 3]).max())
    dr = float(np.abs(pin.log3(target[:3, :3] @ pose[:3, :3].T)).max())
    return dp, dr
