"""``bt-manip bim-report REPORT.json --png OUT.png``: the floor plan of an installation run.

The walls of the run's world (cut at their doors) are drawn in grey, furniture as outlines,
each scheduled element's planned place as a dashed outline, and each element where it ended
up as a bar coloured by its deviation from its planned pose (green at 0 mm, red at the 20 mm
tolerance and beyond); an element not installed is drawn grey at its planned place and named
so. Headless (matplotlib's Agg backend).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from bt_manip.errors import InputError
from bt_manip.geometry import yaw_of
from bt_manip.sim.world_reader import parse_world

MAX_REPORT_BYTES = 64 * 1024 * 1024
"""Largest report read."""
SCALE_MM = 20.0
"""Deviation (mm) at the red end of the colour scale: the placement tolerance."""


def read_report(path: Path) -> dict[str, Any]:
    """The run report at ``path``, which must hold an ``as_built`` table; InputError if not."""
    where = str(path)
    try:
        if not path.is_file():
            raise InputError.single(where, None, "no such report file")
        if path.stat().st_size > MAX_REPORT_BYTES:
            raise InputError.single(
                where, None, f"larger than the limit of {MAX_REPORT_BYTES // 2**20} MB"
            )
        data = json.loads(path.read_text())
    except OSError as exc:
        raise InputError.single(where, None, f"cannot read it: {exc.strerror}") from None
    except ValueError as exc:
        raise InputError.single(where, None, f"not JSON: {exc}") from None
    if not isinstance(data, dict) or not isinstance(data.get("as_built"), list):
        raise InputError.single(
            where, None,
            "no as_built table: it is written by `bt-manip run --report` in a world made by "
            "`bt-manip bim`",
        )
    return data


def bar(ax: Any, pose: list[float], size: list[float], **style: Any) -> None:
    """A rectangle of ``size`` (length, width) centred at ``pose`` (x, y, _, yaw)."""
    from matplotlib.patches import Polygon

    x, y, yaw = pose[0], pose[1], pose[3]
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy = size[0] / 2, size[1] / 2
    pts = [(x + c * u - s * v, y + s * u + c * v) for u, v in
           ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))]
    ax.add_patch(Polygon(pts, closed=True, **style))


def draw_walls(ax: Any, spec: Any) -> None:
    """The world's walls, cut at their doors, as grey bars."""
    for wall in spec.walls:
        (x0, y0), (x1, y1) = wall.start, wall.end
        length = wall.length
        yaw = math.atan2(y1 - y0, x1 - x0)
        cuts = sorted((d.at - d.width / 2, d.at + d.width / 2) for d in wall.doors)
        pos = 0.0
        for a, b in [*cuts, (length, length)]:
            if a > pos + 1e-6:
                mid = (pos + a) / 2
                bar(ax, [x0 + math.cos(yaw) * mid, y0 + math.sin(yaw) * mid, 0.0, yaw],
                     [a - pos, wall.thickness], facecolor="0.55", edgecolor="none")
            pos = max(pos, b)


def draw_boxes(ax: Any, item: Any, **style: Any) -> None:
    """The boxes of a static body (its parts, turned with it), as outlines or fills."""
    yaw = yaw_of(item.pose.quat)
    c, s = math.cos(yaw), math.sin(yaw)
    for part in item.parts:
        if part.shape != "box":
            continue
        x = item.pose.xyz[0] + c * part.xyz[0] - s * part.xyz[1]
        y = item.pose.xyz[1] + s * part.xyz[0] + c * part.xyz[1]
        bar(ax, [x, y, 0.0, yaw + part.rpy[2]], [part.size[0], part.size[1]], **style)


def plot(report: dict[str, Any], world_path: Path, out: Path) -> None:
    """Draw the floor plan of ``world_path`` with the as-built table of ``report`` to ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import cm, colors

    spec = parse_world(world_path)
    sizes = {o.name: o.parts[0].size for o in spec.objects if o.parts}
    fig, ax = plt.subplots(figsize=(9, 6), dpi=100)
    draw_walls(ax, spec)
    for f in spec.furniture:
        for part in f.parts:
            if part.shape != "box" or abs(part.xyz[0]) + abs(part.xyz[1]) > 1e-9:
                continue
            bar(ax, [f.pose.xyz[0], f.pose.xyz[1], 0.0, yaw_of(f.pose.quat)],
                 [part.size[0], part.size[1]], fill=False, edgecolor="0.7", linewidth=0.8)
    ends = [p for w in spec.walls for p in (w.start, w.end)] or [(0.0, 0.0)]
    middle = (sum(p[0] for p in ends) / len(ends), sum(p[1] for p in ends) / len(ends))
    cmap = matplotlib.colormaps["RdYlGn_r"]
    norm = colors.Normalize(0.0, SCALE_MM)
    for row in report["as_built"]:
        size = sizes.get(row.get("object"), [0.5, 0.05, 0.1])
        planned = row["planned"]
        bar(ax, planned, [size[0], max(size[1], 0.03)], fill=False, edgecolor="0.3",
             linestyle="--", linewidth=0.8)
        placed = row.get("placed")
        label = f"{row.get('order')}. {row.get('name')}"
        if row.get("status") == "installed" or row.get("status") == "out of tolerance":
            colour = cmap(norm(min(float(row["deviation_mm"]), SCALE_MM)))
            bar(ax, placed, [size[0], max(size[1], 0.05)], facecolor=colour,
                 edgecolor="black", linewidth=0.6)
            label += f"\n{row['deviation_mm']:.1f} mm, {row['deviation_deg']:.2f} deg"
        else:
            label += f"\n{row.get('status')}"
        # the label beside the element, on the side towards the middle of the building
        nx, ny = -math.sin(planned[3]), math.cos(planned[3])
        if (middle[0] - planned[0]) * nx + (middle[1] - planned[1]) * ny < 0:
            nx, ny = -nx, -ny
        ax.annotate(label, (planned[0], planned[1]), fontsize=7, ha="center", va="center",
                    xytext=(38 * nx, 16 * ny), textcoords="offset points")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(0.05)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    installed = sum(1 for r in report["as_built"] if r.get("status") == "installed")
    ax.set_title(
        f"As built: {installed} of {len(report['as_built'])} installed "
        f"({Path(str(report.get('world', world_path))).name}, seed {report.get('seed')})"
    )
    colour_bar = fig.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, shrink=0.7)
    colour_bar.set_label("deviation from the planned pose (mm)")
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)
