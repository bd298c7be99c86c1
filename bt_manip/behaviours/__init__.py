"""Robot behaviours for trees: importing this package registers them with the node registry.

- Base: Navigate, Reverse, DriveStraight (onto a pose it faces), GetClear, PlanBaseForGrasp
  (where to park to grasp an object), PlanBaseForPlace (where to park to place the object in
  the hand).
- Arm: MoveJointsSequentially, MoveJoints, MoveToPose (also to an object's grasp frame), Lift,
  MoveToolBy (a straight move by an offset).
- Gripper: OpenGripper, CloseGripper. Attach joints: Attach, Detach.
- Placing: Place (the held object to a target pose), Fasten (fix it to the structure).
- Conditions: IsAttached, IsHolding, ObjectInRegion, ObjectAbove, CarriedClear, ObjectUpright.
- World: SpawnModel, DeleteModel. Regions: DropPoint.
- Localisation: IsLocalized, SetInitialPose.
"""

from bt_manip.behaviours import (
    arm,
    attach,
    base_placement,
    conditions,
    drive_straight,
    fasten,
    get_clear,
    gripper,
    localization,
    navigate,
    place,
    place_base,
    regions,
    tool_moves,
    world_ops,
)

__all__ = [
    "arm",
    "attach",
    "base_placement",
    "conditions",
    "drive_straight",
    "fasten",
    "get_clear",
    "gripper",
    "localization",
    "navigate",
    "place",
    "place_base",
    "regions",
    "tool_moves",
    "world_ops",
]
