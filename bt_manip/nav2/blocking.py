"""The ``block`` world fault for Nav2's planner node: a crate falls on a planned route."""

from __future__ import annotations

from typing import Any

import numpy as np

from bt_manip.behaviours.navigate import BLOCK_CLEARANCE, BLOCK_SIZE
from bt_manip.sim.world_spec import COLOURS, BodySpec, Part, Pose3D, Range2D


def maybe_block(node: Any, polyline: np.ndarray, route: str) -> bool:
    """Draw the ``block`` fault for ``route`` (once per navigation to a goal); when it hits, a
    crate falls at the middle of the part of ``polyline`` at least ``BLOCK_CLEARANCE`` from
    both ends (a route with no such part gets none). True when a crate fell."""
    faults = node.faults()
    if faults is None or not faults.specs or polyline is None or len(polyline) < 2:
        return False
    pts = np.asarray(polyline)[:, :2]
    far = (np.linalg.norm(pts - pts[0], axis=1) >= BLOCK_CLEARANCE) & (
        np.linalg.norm(pts - pts[-1], axis=1) >= BLOCK_CLEARANCE
    )
    if not far.any() or not faults.block(route):
        return False
    world = node.world
    candidates = np.flatnonzero(far)
    x, y = pts[candidates[len(candidates) // 2]]
    n = sum(1 for name in world.movable if name.startswith("dropped_crate"))
    spec = BodySpec(
        name=f"dropped_crate_{n}",
        movable=True,
        parts=[Part("box", (BLOCK_SIZE,) * 3, colour=COLOURS["brown"])],
        urdf=None,
        pose=Pose3D((float(x), float(y), BLOCK_SIZE / 2 + 0.3)),
        planar=False,
        mass=8.0,
        friction=0.9,
        colour=COLOURS["brown"],
        randomize=Range2D(),
        line=0,
    )
    try:
        world.spawn(spec)
    except ValueError:
        return False
    return True
