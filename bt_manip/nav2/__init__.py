"""Nav2's behaviour-tree nodes, so Nav2's own trees run on bt-manip's robots without ROS.

Importing this package registers the nodes (Nav2's IDs, ports and semantics):

- controls: PipelineSequence, RecoveryNode, RoundRobin (:mod:`.controls`);
- decorators: RateController, DistanceController, SpeedController, SingleTrigger,
  GoalUpdatedController (:mod:`.decorators`);
- conditions: GoalUpdated, GlobalUpdatedGoal, AreErrorCodesPresent, WouldAPlannerRecoveryHelp,
  WouldAControllerRecoveryHelp, WouldASmootherRecoveryHelp (:mod:`.conditions`);
  GoalReached, DistanceTraveled, TimeExpired, IsPathValid, IsStuck (:mod:`.progress`);
  TransformAvailable (:mod:`.frames`);
- actions: ComputePathToPose, FollowPath, Spin, BackUp, DriveOnHeading, Wait
  (:mod:`.actions`); ClearEntireCostmap, ClearCostmapAroundRobot, ClearCostmapExceptRegion
  (:mod:`.clearing`); PlannerSelector, ControllerSelector, GoalCheckerSelector,
  SmootherSelector (:mod:`.selectors`); ComputePathThroughPoses, RemovePassedGoals
  (:mod:`.through_poses`); TruncatePath, PathLongerOnApproach (a decorator) and
  InitialPoseReceived (:mod:`.path_nodes`).

The goal is a pose on the blackboard (``--bb "goal=x;y;yaw"`` or a named pose of the world);
paths are :class:`~bt_manip.nav2.path.Nav2Path`; result codes are Nav2's numbers
(:mod:`.errors`). Planning and following are bt-manip's navigation of the robot's base.
"""

from bt_manip.nav2 import (
    actions,
    clearing,
    conditions,
    controls,
    decorators,
    frames,
    path_nodes,
    progress,
    selectors,
    through_poses,
)

__all__ = [
    "actions", "clearing", "conditions", "controls", "decorators", "frames", "path_nodes",
    "progress", "selectors", "through_poses",
]
