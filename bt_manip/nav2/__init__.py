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
  InitialPoseReceived (:mod:`.path_nodes`); SmoothPath (:mod:`.smoothing`);
  TruncatePathLocal (:mod:`.path_local`); CancelControl, CancelBackUp, CancelSpin,
  CancelWait, CancelDriveOnHeading (:mod:`.cancel`);
- IsBatteryLow on the robot's simulated battery (:mod:`.battery`); the decorator GoalUpdater
  (:mod:`.goal_updater`);
- current Nav2's ValidatePath, IsGoalNearby, PathExpiringTimer, IsWithinPathTrackingBounds
  (:mod:`.path_checks`), ProgressCheckerSelector, PathHandlerSelector (:mod:`.selectors`);
  GetCurrentPose, GetPoseFromPath, ArePosesNear, ConcatenatePaths, GetNextFewGoals,
  AppendGoalPoseToGoals (:mod:`.pose_nodes`); the route server's ComputeRoute,
  ExtractRouteNodesAsGoals and WouldARouteRecoveryHelp (:mod:`.route`) on the world's route
  graph (:mod:`.route_graph`); ReinitializeGlobalLocalization on the run's particle filter
  (:mod:`.localization`).

The TreeNodesModel names the ports' types as Nav2 does (:mod:`.model_types`).

The goal is a pose on the blackboard (``--bb "goal=x;y;yaw"`` or a named pose of the world);
paths are :class:`~bt_manip.nav2.path.Nav2Path`; result codes are Nav2's numbers
(:mod:`.errors`). Planning and following are bt-manip's navigation of the robot's base.
"""

from bt_manip.bt.registry import registry
from bt_manip.nav2 import (
    actions,
    battery,
    cancel,
    clearing,
    conditions,
    controls,
    decorators,
    frames,
    goal_updater,
    localization,
    path_checks,
    path_local,
    path_nodes,
    pose_nodes,
    progress,
    route,
    selectors,
    smoothing,
    through_poses,
)
from bt_manip.nav2.model_types import apply_model_types

apply_model_types(registry)

__all__ = [
    "actions", "battery", "cancel", "clearing", "conditions", "controls", "decorators",
    "frames", "goal_updater", "localization", "path_checks", "path_local", "path_nodes",
    "pose_nodes", "progress", "route", "selectors", "smoothing", "through_poses",
]
