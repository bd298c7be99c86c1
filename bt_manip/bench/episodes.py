"""One episode of a bench: run it, condense its report into an :class:`EpisodeResult`.

:func:`run_one` is what a worker runs (a process of the pool, or a Ray task); its result is
small enough to send between processes, and is the record every other module of the bench
reads and writes. :data:`SCHEMA_VERSION` is the version of the bench's output formats.
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from bt_manip.bt.status import NodeStatus
from bt_manip.bt.walk import children_of, walk_nodes
from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.groot.monitor import watch
from bt_manip.run.node_counts import COUNT_FIELDS

SCHEMA_VERSION = 3
"""Version of the bench's output formats (episodes.jsonl, episodes.json, summary.json,
episodes.csv, coverage.json); documented by the JSON Schemas in docs/schemas/. Version 1 had
none written; version 2 had no per-node counts in the episodes (``coverage``)."""


@dataclass
class EpisodeResult:
    """The outcome of one episode, small enough to send between processes."""

    seed: int
    status: str
    reason: str
    sim_time: float
    wall_time: float
    ticks: int
    failed_node: str = ""
    """On FAILURE, the node whose failure ended the episode: ``name (ID)``, or its ID."""
    injected: list[dict[str, Any]] = field(default_factory=list)
    metrics: dict[str, float] = field(default_factory=dict)
    """Numeric entries of the root blackboard at the end (counters a tree keeps)."""
    leaf_failures: dict[str, int] = field(default_factory=dict)
    """Per action node (by path), how many times it failed during the episode."""
    coverage: dict[str, list[int]] = field(default_factory=dict)
    """Per node ticked in the episode (by path): its counts, in the order of
    :data:`bt_manip.run.node_counts.COUNT_FIELDS` (ticks, success, failure, skipped, halted)."""
    localization: dict[str, float] | None = None
    """With localisation on, the run report's ``localization`` errors; None (left out of the
    JSON) otherwise."""

    @property
    def success(self) -> bool:
        return self.status == "SUCCESS"

    def to_json(self) -> dict[str, Any]:
        """The record as JSON (``localization`` only when the episode localised)."""
        data = asdict(self)
        if self.localization is None:
            del data["localization"]
        return data


def run_one(spec: EpisodeSpec) -> EpisodeResult:
    """Run one episode (in a worker process) and condense its report.

    The wall time counts the whole episode, building its world and loading its tree included
    (the run report's own wall time counts the ticks only).

    With ``spec.btlog`` set, the episode's .btlog is kept only when it did not succeed."""
    wall0 = time.perf_counter()
    with Episode(spec) as episode:
        leaf_failures = count_leaf_failures(episode.tree)
        report = episode.run()
        metrics = {
            k: float(v)
            for k, v in episode.tree.blackboard.as_dict().items()
            if isinstance(v, int | float) and not isinstance(v, bool)
        }
    wall_time = time.perf_counter() - wall0
    if report.status == "INTERRUPTED":  # Ctrl-C while the episode ran: the runner halted the
        raise KeyboardInterrupt         # tree; the bench stops, this episode did not finish
    if spec.btlog and report.status == "SUCCESS":
        Path(spec.btlog).unlink(missing_ok=True)
    failed_node = ""
    if report.status == "FAILURE" and report.cause:
        name, node_id = report.cause["name"], report.cause["node"]
        failed_node = node_id if name == node_id else f"{name} ({node_id})"
    return EpisodeResult(
        seed=spec.seed,
        status=report.status,
        reason=report.reason,
        sim_time=report.sim_time,
        wall_time=wall_time,
        ticks=report.ticks,
        failed_node=failed_node,
        injected=list(report.extra.get("injected", [])),
        metrics=metrics,
        leaf_failures=dict(leaf_failures),
        coverage={n.path: [n.counts[k] for k in COUNT_FIELDS]
                  for n in report.nodes if n.counts and n.counts["ticks"]},
        localization=dict(report.localization) if report.localization is not None else None,
    )


def count_leaf_failures(tree: Any) -> Counter[str]:
    """A counter, kept up to date while ``tree`` runs, of the times each action node (a leaf
    that is not a condition, by its path) goes to FAILURE."""
    counts: Counter[str] = Counter()
    for walked in walk_nodes(tree.root):
        if children_of(walked.node) or getattr(walked.node, "KIND", "Action") == "Condition":
            continue

        def changed(node: Any, previous: Any, new: Any, path: str = walked.path) -> None:
            if new is NodeStatus.FAILURE:
                counts[path] += 1

        watch(walked.node, changed)
    return counts
