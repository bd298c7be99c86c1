"""The ``block`` world fault for Nav2's nodes: a crate falls in front of the robot on a planned
route.

A planner node draws the fault once per goal (:func:`maybe_block`, as Navigate does); the crate
does not fall at once but when FollowPath brings the robot within
:data:`~bt_manip.run.faults.BLOCK_NEAR` of its place (:func:`drop_if_due`). A crate that appears so
close is on the path the robot is following: the controller stops for it, and the tree's
recoveries and replanning have to get the robot round it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bt_manip.run.faults import drop_crate, plan_block


def maybe_block(node: Any, polyline: np.ndarray, route: str) -> bool:
    """Draw the ``block`` fault for ``route`` for the node's robot; True when a crate is due
    on it (it falls later, see :func:`drop_if_due`)."""
    faults = node.faults()
    if faults is None:
        return False
    block = plan_block(faults, polyline, route)
    if block is None:
        return False
    faults.defer_block(node.robot_name(), block)
    return True


def drop_if_due(node: Any, x: float, y: float) -> str | None:
    """Drop the crate due on the route of the node's robot when (``x``, ``y``), the robot's
    position, is near its place; the crate's name, or None."""
    faults = node.faults()
    if faults is None:
        return None
    block = faults.due_block(node.robot_name(), x, y)
    if block is None:
        return None
    return drop_crate(node.world, faults, block)
