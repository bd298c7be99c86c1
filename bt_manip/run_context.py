"""The run context, under its former name: :mod:`bt_manip.run.context` holds it now.

``from bt_manip.run_context import RunContext`` goes on working; new code imports from
:mod:`bt_manip.run.context`.
"""

from __future__ import annotations

from bt_manip.run.context import (
    IK_MAX_RESTARTS,
    IK_POSTURE_WEIGHT,
    IK_TOLERANCE,
    ArmIK,
    Cancellable,
    RobotServices,
    RunContext,
    RunningActions,
    run_overlay,
)

__all__ = [
    "IK_MAX_RESTARTS", "IK_POSTURE_WEIGHT", "IK_TOLERANCE", "ArmIK", "Cancellable",
    "RobotServices", "RunContext", "RunningActions", "run_overlay",
]
