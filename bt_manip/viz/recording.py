"""A recorded run in memory: the bodies as they came and went, their pose samples, the tree's
status changes and the overlay items, as :class:`~bt_manip.viz.recorder.Recorder` takes them
and :mod:`bt_manip.viz.replay_page` writes them."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bt_manip.viz.scene import SceneBody, SceneObject


@dataclass
class RecordedBody:
    """One body in a recording: its drawing, when it was in the world, and its samples.

    ``key`` names it in the recording (its name; ``name~2`` for the second body of that name,
    when a model is spawned again after being deleted). ``samples[j]`` belongs to frame
    ``first_frame + j``; a body without moving frames has no samples.
    """

    key: str
    drawing: SceneBody
    appear: float
    disappear: float | None = None
    first_frame: int = 0
    samples: list[np.ndarray] = field(default_factory=list)


@dataclass
class Recording:
    """Everything a replay page needs, in memory."""

    bodies: list[RecordedBody]
    nodes: list[dict[str, Any]]
    times: list[float] = field(default_factory=list)
    status_events: list[tuple[float, int, int, str]] = field(default_factory=list)
    overlay_events: list[tuple[float, str, dict[str, Any] | None, list[float] | None]] = field(
        default_factory=list
    )
    highlight_events: list[tuple[float, str, bool]] = field(default_factory=list)
    """(time, body key, held)"""
    result: str = ""
    info: dict[str, Any] = field(default_factory=dict)
    counts: list[list[int]] | None = None
    """Per node (in the order of ``nodes``), its counts of the run: ticks, success, failure,
    skipped, halted (:mod:`bt_manip.run.node_counts`); None when the run could not count."""

    @property
    def objects(self) -> list[SceneObject]:
        """Every drawable of every body that was ever in the world."""
        return [o for b in self.bodies for o in b.drawing.objects]

    def track_samples(self, path: str) -> tuple[int, np.ndarray]:
        """First frame and samples (rows x, y, z, qx, qy, qz, qw) of one moving frame."""
        for body in self.bodies:
            if path in body.drawing.tracks:
                k = body.drawing.tracks.index(path)
                return body.first_frame, np.array([s[k] for s in body.samples])
        raise KeyError(path)
