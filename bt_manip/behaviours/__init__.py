"""Robot behaviours for trees: importing this package registers them with the node registry.

- Base: Navigate, Reverse, PlanBaseForGrasp (where to park to grasp an object).
- Arm: MoveJointsSequentially, MoveJoints, MoveToPose (also to an object's grasp frame), Lift.
- Gripper: OpenGripper, CloseGripper. Attach joints: Attach, Detach.
- Conditions: IsAttached, IsHolding, ObjectInRegion, ObjectAbove, CarriedClear, ObjectUpright.
- World: SpawnModel, DeleteModel.
"""

from bt_manip.behaviours import (
    arm,
    attach,
    base_placement,
    conditions,
    gripper,
    navigate,
    world_ops,
)

__all__ = [
    "arm", "attach", "base_placement", "conditions", "gripper", "navigate", "world_ops"
]
