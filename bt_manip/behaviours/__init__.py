"""Robot behaviours for trees: importing this package registers them with the node registry.

- Base: Navigate, Reverse, GetClear.
- Arm: MoveJointsSequentially, MoveJoints, MoveToPose, Lift.
- Gripper: OpenGripper, CloseGripper. Attach joints: Attach, Detach.
- Conditions: IsAttached, IsHolding, ObjectInRegion, ObjectAbove, CarriedClear.
- World: SpawnModel, DeleteModel. Regions: DropPoint.
"""

from bt_manip.behaviours import (
    arm,
    attach,
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
    "conditions",
    "get_clear",
    "gripper",
    "navigate",
    "regions",
    "world_ops",
]
