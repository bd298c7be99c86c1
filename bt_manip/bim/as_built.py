"""The as-built table of an installation run: where each element of the schedule ended up.

A world written by ``bt-manip bim`` has ``schedule.json`` beside it, naming it as its world.
After a run in that world, :func:`as_built` reads each element's true pose from the simulator
and compares it with its planned (BIM) pose. One row per element, in schedule order:

- ``global_id``, ``name``, ``object``, ``order``;
- ``planned``: the target pose ``[x, y, z, yaw]`` (m, rad);
- ``placed``: the element's pose at the end of the run, the same way;
- ``deviation_mm``, ``deviation_deg``: distance of the centres and rotation between the two
  (:mod:`bt_manip.manipulation.placing`: a box turned half a turn is the same box);
- ``fastened_to``: the structure it is fixed to, or null;
- ``status``: ``installed`` (fastened within the tolerance), ``out of tolerance`` (fastened
  outside it), ``in hand`` (still attached to the robot), ``not fastened`` (loose within
  :data:`NEAR_TARGET` of its target) or ``not installed`` (anywhere else: at the stock).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from bt_manip.manipulation.perception import true_pose
from bt_manip.manipulation.placing import Target, deviation, yaw_of_matrix
from bt_manip.sim.fasteners import fastenings

POSITION_TOLERANCE = 0.02
"""Largest distance (m) of an installed element's centre from its planned one."""
ANGLE_TOLERANCE = math.radians(2.0)
"""Largest rotation (rad) of an installed element from its planned pose."""
NEAR_TARGET = 0.3
"""A loose element within this distance (m) of its target was set down there, not fastened."""
MAX_SCHEDULE_BYTES = 16 * 1024 * 1024
"""Largest schedule.json read."""


def schedule_for(world_path: str | Path) -> dict[str, Any] | None:
    """The ``schedule.json`` beside ``world_path`` when it names that world, else None."""
    world = Path(world_path)
    path = world.with_name("schedule.json")
    try:
        if not path.is_file() or path.stat().st_size > MAX_SCHEDULE_BYTES:
            return None
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("world") != world.name:
        return None
    if not isinstance(data.get("elements"), list):
        return None
    return data


def _pose_list(pose: Any) -> list[float]:
    x, y, z = (float(v) for v in pose[:3, 3])
    return [round(x, 4), round(y, 4), round(z, 4), round(yaw_of_matrix(pose), 4)]


def as_built(world: Any, schedule: dict[str, Any]) -> list[dict[str, Any]]:
    """The table (see the module docstring) for the elements of ``schedule`` in ``world``."""
    fixed = fastenings(world)
    rows = []
    for e in schedule["elements"]:
        name = e.get("object")
        t = e.get("target", {})
        target = Target(float(t["x"]), float(t["y"]), float(t["z"]), float(t["yaw"]))
        row: dict[str, Any] = {
            "order": e.get("order"),
            "global_id": e.get("global_id"),
            "name": e.get("name"),
            "object": name,
            "planned": [round(v, 4) for v in (target.x, target.y, target.z, target.yaw)],
            "placed": None,
            "deviation_mm": None,
            "deviation_deg": None,
            "fastened_to": fixed.get(name),
            "status": "not installed",
        }
        if name not in world.movable:
            rows.append(row)
            continue
        pose = true_pose(world, world.movable[name])
        dev = deviation(pose, target)
        row["placed"] = _pose_list(pose)
        row["deviation_mm"] = round(dev.mm, 1)
        row["deviation_deg"] = round(dev.deg, 2)
        if name in fixed:
            ok = dev.within(POSITION_TOLERANCE, ANGLE_TOLERANCE)
            row["status"] = "installed" if ok else "out of tolerance"
        elif world.attachments.is_attached(name):
            row["status"] = "in hand"
        elif dev.distance <= NEAR_TARGET:
            row["status"] = "not fastened"
        rows.append(row)
    return rows


def table_text(rows: list[dict[str, Any]]) -> str:
    """The table as text for the console."""
    lines = ["as built:"]
    for r in rows:
        dev = (
            f"{r['deviation_mm']:.1f} mm, {r['deviation_deg']:.2f} deg"
            if r["deviation_mm"] is not None and r["status"] != "not installed" else "-"
        )
        lines.append(f"  {r['order']}. {r['name']} ({r['global_id']}): {r['status']}, {dev}")
    return "\n".join(lines)
