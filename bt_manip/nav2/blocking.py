"""The ``block`` world fault for Nav2's planner nodes: a crate falls on a planned route."""

from __future__ import annotations

from typing import Any

import numpy as np

from bt_manip.faults import block_route


def maybe_block(node: Any, polyline: np.ndarray, route: str) -> bool:
    """Draw the ``block`` fault for ``route`` (once per navigation to a goal), as Navigate does
    (:func:`bt_manip.faults.block_route`). True when a crate fell."""
    faults = node.faults()
    if faults is None:
        return False
    return block_route(node.world, faults, polyline, route) is not None
