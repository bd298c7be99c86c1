"""coverage.png: the tree coloured by coverage, laid out as the live tree page lays it out.

One row per node in depth-first order, indented by depth (the rows of the tree page), each with
a chip coloured by what the bench's episodes did with it: never ticked, ticked, a branch node
whose branches all ran, a branch node with branches that never ran. A recovery that never ran
is marked in red. On the right: the episodes the node was ticked in, and how often its ticks
returned SUCCESS, FAILURE, SKIPPED, and how often it was halted while RUNNING. The figure is
drawn from coverage.json's data (:meth:`bt_manip.bench.coverage.BenchCoverage.to_json`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

COVERAGE_COLOURS = {
    "never ticked": "#c7c7c7",
    "ticked": "tab:blue",
    "branches all ran": "tab:green",
    "branches not all ran": "tab:orange",
}
"""Chip colour of each kind of node, as the legend names them."""
RECOVERY_NEVER_RAN = "tab:red"
COUNTED = ("success", "failure", "skipped", "halted")
"""The counts shown on the right, each in its column (x of its right edge in COLUMNS)."""
COLUMNS = (77.0, 84.0, 91.0, 98.0)
MAX_ROWS = 400
"""Rows drawn at most (a larger tree is cut, with a note)."""


def node_state(node: dict[str, Any], branch_node: dict[str, Any] | None) -> str:
    """The key of :data:`COVERAGE_COLOURS` for a node of coverage.json."""
    if not node["episodes"]:
        return "never ticked"
    if branch_node is not None:
        return ("branches all ran" if branch_node["covered"] == branch_node["total"]
                else "branches not all ran")
    return "ticked"


def coverage_figure(data: dict[str, Any]) -> Any:
    """The figure of coverage.png for a coverage.json's ``data``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    nodes = data["nodes"][:MAX_ROWS]
    branch_nodes = {b["path"]: b for b in data["branch_nodes"]}
    never = {r["path"] for r in data["recoveries"]["never_exercised"]}
    depth = max((n["path"].count("/") for n in nodes), default=0)
    rows = len(nodes)
    fig_h = 1.3 + 0.24 * rows
    fig, ax = plt.subplots(figsize=(12, fig_h))
    ax.set_xlim(0, 100)
    ax.set_ylim(rows + 0.5, -1.5)
    ax.axis("off")
    indent = min(2.2, 40.0 / max(1, depth + 1))
    runs = data["runs"]
    ax.text(70, -0.9, "episodes", fontsize=8, ha="right", weight="bold")
    for x, head in zip(COLUMNS, COUNTED, strict=True):
        ax.text(x, -0.9, head, fontsize=8, ha="right", weight="bold")
    for i, n in enumerate(nodes):
        x = 1 + indent * n["path"].count("/")
        state = node_state(n, branch_nodes.get(n["path"]))
        missed = n["path"] in never
        ax.add_patch(plt.Rectangle((x, i - 0.35), 1.2, 0.7, color=COVERAGE_COLOURS[state],
                                   ec=RECOVERY_NEVER_RAN if missed else "none", lw=1.5))
        label = n["name"] + (f"  [{n['node']}]" if n["node"] != n["name"] else "")
        if n["path"] in branch_nodes:
            b = branch_nodes[n["path"]]
            label += f"  {b['covered']}/{b['total']} branches"
        if missed:
            label += "  recovery never ran"
        ax.text(x + 1.8, i, label, va="center", fontsize=8,
                color=RECOVERY_NEVER_RAN if missed else "black")
        ax.text(70, i, f"{n['episodes']}/{runs}", va="center", ha="right", fontsize=8)
        for x, head in zip(COLUMNS, COUNTED, strict=True):
            ax.text(x, i, str(n[head]), va="center", ha="right", fontsize=8)
    if len(data["nodes"]) > rows:
        ax.text(1, rows, f"... {len(data['nodes']) - rows} more nodes in coverage.json",
                fontsize=8)
    b = data["branch_coverage"]
    rec = data["recoveries"]
    share = f"{100.0 * b['covered'] / b['total']:.0f} %" if b["total"] else "no branches"
    ax.set_title(f"{Path(str(data.get('tree', ''))).name}: {b['covered']}/{b['total']} "
                 f"branches ran ({share}), {rec['exercised']}/{rec['total']} recoveries "
                 f"exercised, {runs} episodes", fontsize=10)
    handles = [Patch(color=c, label=k) for k, c in COVERAGE_COLOURS.items()]
    handles.append(Patch(facecolor="white", edgecolor=RECOVERY_NEVER_RAN,
                         label="recovery never ran"))
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=8, frameon=False)
    fig.subplots_adjust(left=0.01, right=0.99, top=1 - 0.45 / fig_h, bottom=0.5 / fig_h)
    return fig


def write_coverage_png(data: dict[str, Any], path: Path) -> None:
    """Write :func:`coverage_figure` to ``path`` (PNG)."""
    import matplotlib.pyplot as plt

    fig = coverage_figure(data)
    fig.savefig(path, dpi=90)
    plt.close(fig)
