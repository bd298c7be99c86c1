"""Arm kinematics: Pinocchio arm models, the CasADi forward-kinematics graph and the IK solver.

>>> from bt_manip.kinematics import ArmModel, IKSolver, IKOptions
>>> arm = ArmModel.from_urdf(path, base_link="base_link", tip_link="tool0")
>>> res = IKSolver(arm, IKOptions()).solve(target_4x4)
>>> res.success, res.q, res.reason
"""

from bt_manip.kinematics.arm_model import ArmModel, ChainJoint, KinematicsError
from bt_manip.kinematics.ik import IKOptions, IKResult, IKSolver

__all__ = ["ArmModel", "ChainJoint", "IKOptions", "IKResult", "IKSolver", "KinematicsError"]
