"""The run report: what happened in a run, as ``--report`` writes it and the console sums it up.

:class:`RunReport` is written as JSON with ``schema_version`` :data:`REPORT_SCHEMA_VERSION`
(documented by docs/schemas/run-report.schema.json); :meth:`RunReport.summary` is the text that
``bt-manip run`` prints at the end. :func:`node_reports` reads every node's final state.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from bt_manip.bt.node import BtNode
from bt_manip.bt.status import as_status
from bt_manip.bt.walk import walk_nodes
from bt_manip.outputs import write_text
from bt_manip.run.failure_cause import FailureCause
from bt_manip.run.jit_clock import JIT_NOTE_S
from bt_manip.run.node_counts import NodeCounter
from bt_manip.run.status import RunStatus

REPORT_SCHEMA_VERSION = 1
"""Version of the run report's JSON format (``--report``); bumped when a field changes meaning
or goes away."""


@dataclass
class NodeReport:
    """A node's final state for the report: ``status`` now (finished nodes are IDLE again, as
    in BehaviorTree.CPP) and ``last_status``, what it last returned."""

    path: str
    node: str
    status: str
    reason: str = ""
    last_status: str = ""
    counts: dict[str, int] | None = None
    """How often the node was ticked in the run and what it returned: ``ticks``, ``success``,
    ``failure``, ``skipped``, and ``halted`` (stopped while RUNNING); see
    :mod:`bt_manip.run.node_counts`. None for a tree whose ticks cannot be watched (a plain
    py_trees tree)."""


@dataclass
class RunReport:
    """What happened in a run; written as JSON by ``--report`` (with ``schema_version``
    :data:`REPORT_SCHEMA_VERSION`, documented by docs/schemas/run-report.schema.json)."""

    status: RunStatus
    reason: str
    sim_time: float
    wall_time: float
    ticks: int
    jit_time: float = 0.0
    """Seconds of ``wall_time`` numba spent compiling kernels (the first run after an install)
    or loading them from its cache (milliseconds): :mod:`bt_manip.run.jit_clock`."""
    tree: str = ""
    world: str = ""
    seed: int | None = None
    nodes: list[NodeReport] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)
    cause: dict[str, str] = field(default_factory=dict)
    """On FAILURE, the node whose failure ended the run: ``path``, ``name``, ``node`` (its ID)
    and ``reason``; empty otherwise."""
    as_built: list[dict[str, Any]] | None = None
    """In a world written by ``bt-manip bim``: each scheduled element's planned and placed pose,
    deviation and status (:mod:`bt_manip.bim.as_built`, added by the episode); None
    elsewhere."""
    localization: dict[str, float] | None = None
    """With localisation on: the believed pose's error against the truth over the run
    (``mean_error_m``, ``p95_error_m``, ``max_error_m``, ``mean_yaw_error_rad``,
    ``time_over_0_2m_s``); None (not in the JSON) otherwise."""
    costmap: dict[str, int] | None = None
    """With localisation on: the robot's laser-fed costmaps (per costmap, ``global_`` or
    ``local_``: ``marked_cells`` at the end, ``peak_marked_cells``, ``updates``, ``clears``,
    ``cleared_cells``; :meth:`~bt_manip.navigation.layered.RobotCostmaps.report`); None (not
    in the JSON) otherwise."""
    notes: list[str] = field(default_factory=list)
    """Text the summary ends with (the episode adds the as-built table); not in the JSON."""

    def __post_init__(self) -> None:
        self.status = RunStatus(self.status)

    @property
    def exit_code(self) -> int:
        return self.status.exit_code

    @property
    def real_time_factor(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time > 0 else math.inf

    def to_json(self) -> dict[str, Any]:
        data = {"schema_version": REPORT_SCHEMA_VERSION, **asdict(self)}
        data["status"] = self.status.value
        data["real_time_factor"] = (
            round(self.real_time_factor, 3) if math.isfinite(self.real_time_factor) else None
        )
        data["exit_code"] = self.exit_code
        if self.as_built is None:
            del data["as_built"]
        if self.localization is None:
            del data["localization"]
        if self.costmap is None:
            del data["costmap"]
        for node in data["nodes"]:
            if node["counts"] is None:
                del node["counts"]
        del data["notes"]
        return data

    def write(self, path: str | Path) -> None:
        write_text(path, json.dumps(self.to_json(), indent=2) + "\n")

    def summary(self) -> str:
        rtf = self.real_time_factor
        rtf_text = f"{rtf:.1f}x real time" if math.isfinite(rtf) else "instant"
        lines = [
            f"result: {self.status}" + (f" ({self.reason})" if self.reason else ""),
            f"  sim time {self.sim_time:.2f} s, wall time {self.wall_time:.2f} s "
            f"({rtf_text}), {self.ticks} ticks",
        ]
        if self.jit_time >= JIT_NOTE_S:
            lines.append(
                f"  of which {self.jit_time:.1f} s compiling bt-manip's kernels, once after an "
                "install (later runs load them from numba's cache)")
        if self.localization is not None:
            loc = self.localization
            lines.append(
                f"  localisation error: mean {loc['mean_error_m'] * 100:.1f} cm, p95 "
                f"{loc['p95_error_m'] * 100:.1f} cm, max {loc['max_error_m'] * 100:.1f} cm, "
                f"mean yaw {loc['mean_yaw_error_rad']:.4f} rad, "
                f"{loc['time_over_0_2m_s']:.1f} s over 0.2 m")
        if self.costmap is not None:
            cm = self.costmap
            lines.append(
                f"  costmaps: {cm['global_marked_cells']} cells marked in the global one at the "
                f"end (peak {cm['global_peak_marked_cells']}), {cm['local_marked_cells']} in "
                f"the local one; clears: global {cm['global_clears']}, local "
                f"{cm['local_clears']}")
        cause = self.cause.get("path")
        failed = [n for n in self.nodes if "FAILURE" in (n.status, n.last_status) and n.reason]
        failed.sort(key=lambda n: n.path != cause)  # the failure that ended the run first
        for n in failed[:10]:
            ended = " (ended the run)" if n.path == cause else ""
            lines.append(f"  FAILURE {n.path} [{n.node}]: {n.reason}{ended}")
        lines.extend(self.notes)
        return "\n".join(lines)


def cause_json(cause: FailureCause | None) -> dict[str, str]:
    """The report's ``cause``: the node whose failure ended the run, or {}."""
    if cause is None:
        return {}
    return {"path": cause.path, "name": cause.name, "node": cause.node_id, "reason": cause.reason}


def node_reports(tree: Any, counter: NodeCounter | None = None) -> list[NodeReport]:
    """Every node of ``tree`` (a bt-manip tree or anything with a py_trees ``root``) with its
    status and feedback, in the order and with the paths of :func:`bt_manip.bt.walk.walk_nodes`;
    with ``counter``, each with its counts of the run.
    """
    root = getattr(tree, "root", None)
    if root is None:
        return []
    out: list[NodeReport] = []
    for walked in walk_nodes(root):
        node = walked.node
        if isinstance(node, BtNode):
            status, last = node.bt_status.value, node.last_status.value
        else:
            status = last = as_status(node.status).value
        out.append(NodeReport(walked.path, walked.node_id, status,
                              node.feedback_message or "", last,
                              counter.of(walked.path) if counter is not None else None))
    return out
