"""Robot behaviours for trees: importing this package registers them with the node registry.

- Base: Navigate, Reverse, GetClear, PlanBaseForGrasp (where to park to grasp an object).
- Arm: MoveJointsSequentially, MoveJoints, MoveToPose (also to an object's grasp frame), Lift.
- Gripper: OpenGripper, CloseGripper. Attach joints: Attach, Detach.
- Conditions: IsAttached, IsHolding, ObjectInRegion, ObjectAbove, CarriedClear, ObjectUpright.
- World: SpawnModel, DeleteModel. Regions: DropPoint.
"""

from bt_manip.behaviours import (
    arm,
    attach,
    base_placement,
    conditions,
    get_clear,
    gripper,
    navigate,
    regions,
    world_ops,
)

__all__ = [
    "arm",
    "attach",
    "base_placement",
    "conditions",
    "get_clear",
    "gripper",
    "navigate",
    "regions",
    "world_ops",
]
