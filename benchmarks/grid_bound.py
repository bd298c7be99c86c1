"""A navigation grid at the cell bound: peak memory and CPU time of building it and planning.

Run: ``.venv/bin/python benchmarks/grid_bound.py [--cells N] [--png DIR]``

Writes a world file of a few hundred bytes: a square room whose occupancy grid (0.05 m cells,
obstacles plus the 0.5 m margin) has just under ``--cells`` cells (default
:data:`bt_manip.navigation.grid.MAX_CELLS`), four walls and a long wall across the middle with
gaps at both ends, and a crate. It loads the world with a Husky in the west half, builds the robot's
:class:`~bt_manip.navigation.navigator.Navigator` (rasterising, clearance, cost grid) and plans
to the far side of the middle wall (A*, shortcuts), the work a ``Navigate`` does before the
robot moves. With ``--png DIR`` it also writes the occupancy and cost images. With ``--carry``
the navigator counts a crate beside the robot as carried, so the plan is the search over poses
(:mod:`bt_manip.navigation.lattice`) to a goal 12 m away, with its two clearance layers.

Prints one JSON line: the grid's shape and cell count, the plan's outcome and length, the CPU
seconds (user + system) of each phase, the process's peak resident memory before the grid and
at the end (MB), and the peak per grid cell above the baseline (bytes).
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import sys
import tempfile
from pathlib import Path

from bt_manip.cli.args import positive
from bt_manip.navigation.grid import MAX_CELLS, save_cost_png
from bt_manip.navigation.navigator import Navigator
from bt_manip.sim.world import World

RESOLUTION = 0.05
PAD = 0.5
THICKNESS = 0.15


def cpu() -> float:
    """CPU seconds (user + system) of this process so far."""
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime


def peak_mb() -> float:
    """Peak resident memory of this process so far (MB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def world_text(cells: int) -> tuple[str, float]:
    """A square room whose grid has at most ``cells`` cells, and its half side (m)."""
    side_cells = math.isqrt(cells) - 2  # room for rounding the extent out to whole cells
    span = side_cells * RESOLUTION  # outer extent of the walls plus the margin on each side
    half = round((span - 2 * PAD - THICKNESS) / 2.0, 2) - 0.01
    walls = [
        ("north", (-half, half), (half, half)),
        ("south", (-half, -half), (half, -half)),
        ("east", (half, -half), (half, half)),
        ("west", (-half, -half), (-half, half)),
        ("middle", (0.0, -half + 4.0), (0.0, half - 4.0)),
    ]
    lines = ["name: grid_bound", "walls:"]
    for name, a, b in walls:
        lines.append(
            f"  - {{name: {name}, from: [{a[0]:.2f}, {a[1]:.2f}], to: [{b[0]:.2f}, {b[1]:.2f}], "
            f"thickness: {THICKNESS}, height: 1.5}}"
        )
    lines.append("objects:")
    lines.append(
        f"  - {{name: crate, shape: box, size: [0.3, 0.3, 0.3], mass: 1.0, "
        f"pose: [{-half / 2 + 1.5:.2f}, 0, 0]}}"
    )
    lines.append("robots:")
    lines.append(f"  - {{name: husky, description: husky_ur3, pose: [{-half / 2:.2f}, 0, 0]}}")
    return "\n".join(lines) + "\n", half


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=positive(int), default=MAX_CELLS)
    ap.add_argument("--png", type=Path, default=None, help="write the grid images here")
    ap.add_argument(
        "--carry",
        action="store_true",
        help="count the crate as carried: the plan is a search over poses",
    )
    args = ap.parse_args(argv)
    text, half = world_text(args.cells)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "grid_bound.yaml"
        path.write_text(text)
        world = World(path)
        robot = world.robots["husky"]
        base_mb = peak_mb()
        t0 = cpu()
        nav = Navigator(robot, world.obstacle_body_ids(), world.movable)
        if args.carry:  # the navigator's view of a held crate (nothing is gripped)
            nav.attach(world.body_id("crate"), "crate")
        t1 = cpu()
        cost = nav.cost
        t2 = cpu()
        start = robot.base_pose2d()
        goal = (-half / 2.0 + 12.0, 4.0, 0.0) if args.carry else (half / 2.0, half / 2.0, 0.0)
        plan = nav.start(start, goal)
        t3 = cpu()
        if args.png is not None:
            args.png.mkdir(parents=True, exist_ok=True)
            nav.costmap.grid.save_png(args.png / "occupancy.png", plan.cells)
            save_cost_png(args.png / "cost.png", cost, plan.cells)
        t4 = cpu()
        cells = nav.static.occupied.size
        end_mb = peak_mb()
        world.close()
    row = {
        "bench": "grid_bound" + (" carrying" if args.carry else ""),
        "world_bytes": len(text),
        "grid": list(nav.static.shape),
        "cells": cells,
        "plan": plan.outcome.value,
        "length_m": round(plan.length, 2),
        "cpu_s": {
            "grid_and_clearance": round(t1 - t0, 2),
            "cost_grid": round(t2 - t1, 2),
            "plan": round(t3 - t2, 2),
            "png": round(t4 - t3, 2),
            "total": round(t4 - t0, 2),
        },
        "peak_mb_before": round(base_mb, 1),
        "peak_mb": round(end_mb, 1),
        "bytes_per_cell": round((end_mb - base_mb) * 2**20 / cells, 1),
    }
    print(json.dumps(row))
    return 0


if __name__ == "__main__":
    sys.exit(main())
