"""``bt-manip bim ... --png FILE.png``: the top view of a converted world, to see what was read.

Drawn like the as-built plot (:mod:`~bt_manip.bim.as_built_plot`): the walls cut at their doors
in grey, curtain walls in cyan, other obstacles and furniture as outlines, each space's outline
dashed with its name, the stock's stands and the elements waiting in them, each element's target
place as a dashed bar numbered in schedule order, and the robot's start. Headless (Agg).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from bt_manip.bim.as_built_plot import bar, draw_boxes, draw_walls
from bt_manip.sim.world_reader import parse_world


def plot_world(conversion: Any, out: Path) -> None:
    """Draw the world of ``conversion`` (a :class:`~bt_manip.bim.convert.Conversion`) to
    ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    spec = parse_world(conversion.world_path)
    building = conversion.building
    curtain = {f.name for f in building.curtain_walls}
    stands = {f"stand_{e.object}" for e in conversion.elements}
    fig, ax = plt.subplots(figsize=(10, 7), dpi=100)
    draw_walls(ax, spec)
    for item in spec.furniture:
        if item.name in curtain:
            draw_boxes(ax, item, facecolor="#3fb7c9", edgecolor="none")
        elif item.name.startswith("stand_") or item.name in stands:
            draw_boxes(ax, item, facecolor="#d9c8a0", edgecolor="0.4", linewidth=0.5)
        else:
            draw_boxes(ax, item, fill=False, edgecolor="0.45", linewidth=0.8)
    for obj in spec.objects:
        draw_boxes(ax, obj, facecolor="#e08a2c", edgecolor="black", linewidth=0.5)
    for space in building.spaces:
        b = space.box
        bar(ax, [b.centre[0], b.centre[1], 0.0, b.yaw], [b.size[0], b.size[1]], fill=False,
            edgecolor="#6a8fd0", linestyle="--", linewidth=0.8)
        ax.annotate(space.name, (b.centre[0], b.centre[1]), fontsize=7, ha="center",
                    va="center", color="#2d4f8f")
    for e in conversion.elements:
        t = e.target
        bar(ax, [t["x"], t["y"], 0.0, t["yaw"]], [e.size[0], max(e.size[1], 0.04)],
            fill=False, edgecolor="#c0392b", linestyle="--", linewidth=1.0)
        ax.annotate(str(e.order), (t["x"], t["y"]), fontsize=7, color="#c0392b",
                    xytext=(0, 6), textcoords="offset points", ha="center")
    x, y, yaw = conversion.start
    ax.plot([x], [y], marker="o", color="#2e7d32")
    ax.annotate("start", (x, y), fontsize=7, color="#2e7d32", xytext=(0, -10),
                textcoords="offset points", ha="center")
    ax.arrow(x, y, 0.4 * math.cos(yaw), 0.4 * math.sin(yaw), width=0.03, color="#2e7d32")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(0.05)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"{Path(str(conversion.source)).name}, storey '{conversion.storey}': "
                 f"{len(spec.walls)} walls, {len(conversion.elements)} elements to install")
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)
