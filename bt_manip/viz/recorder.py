"""Record a run for the replay page: scene once, poses at a fixed rate, tree status changes.

:class:`Recorder` is a run hook. On creation it captures the scene (:mod:`bt_manip.viz.scene`)
and a first frame at the current sim time. After every tick it

- records each node whose status or reason changed (exact tick time),
- samples every moving frame when ``1 / sample_hz`` of sim time has passed since the last
  sample (and always on the last tick),
- records overlay items (planned paths, target frames) and held-object highlights that changed.

:meth:`Recorder.close` writes the self-contained page (:mod:`bt_manip.viz.replay_page`). The
recorder only reads the simulation, so a recorded run ends exactly like an unrecorded one.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bt_manip.viz.live import held_objects
from bt_manip.viz.overlay import FrameItem, item_json
from bt_manip.viz.scene import Scene, build_scene
from bt_manip.viz.tree_state import TreeWatcher, run_result


@dataclass
class RecordOptions:
    """How densely to sample the run."""

    sample_hz: float = 20.0
    """Pose samples per second of sim time (ticks between samples are not drawn)."""
    title: str = ""


@dataclass
class Recording:
    """Everything a replay page needs, in memory."""

    scene: Scene | None
    nodes: list[dict[str, Any]]
    times: list[float] = field(default_factory=list)
    poses: list[np.ndarray] = field(default_factory=list)
    status_events: list[tuple[float, int, int, str]] = field(default_factory=list)
    overlay_events: list[tuple[float, str, dict[str, Any] | None, list[float] | None]] = field(
        default_factory=list
    )
    highlight_events: list[tuple[float, str, bool]] = field(default_factory=list)
    result: str = ""
    info: dict[str, Any] = field(default_factory=dict)


class Recorder:
    """A run hook that records the run and writes a replay page on :meth:`close`.

    Args:
        path: the HTML file to write.
        world: the loaded World, or None (tree statuses only).
        tree: the tree (``root``, optional ``node_records()``).
        options: sampling rate and page title.
    """

    def __init__(self, path: str | Path, world: Any, tree: Any,
                 options: RecordOptions | None = None, info: dict[str, Any] | None = None) -> None:
        self.path = Path(path)
        self.world = world
        self.options = options or RecordOptions()
        self.watcher = TreeWatcher(tree)
        scene = build_scene(world) if world is not None else None
        details = dict(info or {})
        if world is not None:
            details.setdefault("robots", list(getattr(world, "robots", {}) or {}))
        self.rec = Recording(scene, self.watcher.structure(), info=details)
        self._t0 = float(world.time) if world is not None else 0.0
        self._next_sample = 0.0
        self._overlay_version = -1
        self._overlay_items: dict[str, Any] = {}
        self._held: set[str] = set()
        self._last_time = 0.0
        self._closed = False
        self._sample(0.0)
        self._track_overlay(0.0)

    # -- sampling ---------------------------------------------------------------------------
    def _now(self, runner: Any) -> float:
        if self.world is not None:
            return float(self.world.time) - self._t0
        return float(getattr(runner, "sim_time", 0.0))

    def _sample(self, t: float) -> None:
        scene = self.rec.scene
        if scene is None or not scene.tracks:
            if not self.rec.times or t > self.rec.times[-1]:
                self.rec.times.append(t)
            return
        if self.rec.times and t <= self.rec.times[-1]:
            return
        self.rec.times.append(t)
        self.rec.poses.append(scene.read_poses().astype(np.float32))
        self._next_sample = t + 1.0 / self.options.sample_hz - 1e-9

    def _track_overlay(self, t: float) -> None:
        overlay = getattr(self.world, "overlay", None) if self.world is not None else None
        if overlay is None or overlay.version == self._overlay_version:
            return
        self._overlay_version = overlay.version
        for name in list(self._overlay_items):
            if name not in overlay.items:
                self.rec.overlay_events.append((t, name, None, None))
                del self._overlay_items[name]
        for name, item in overlay.items.items():
            previous = self._overlay_items.get(name)
            if previous is item:
                continue
            matrix = [float(v) for v in item.matrix.T.flatten()] if isinstance(
                item, FrameItem) else None
            if isinstance(item, FrameItem) and isinstance(previous, FrameItem) and (
                previous.size == item.size
            ):
                self.rec.overlay_events.append((t, name, None, matrix))
            else:
                obj = item_json(item)
                if isinstance(item, FrameItem):
                    obj["object"]["matrix"] = [1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0,
                                               1.0]
                self.rec.overlay_events.append((t, name, obj, matrix))
            self._overlay_items[name] = item

    def _track_highlights(self, t: float) -> None:
        if self.world is None:
            return
        held = held_objects(self.world)
        for name in sorted(held ^ self._held):
            self.rec.highlight_events.append((t, name, name in held))
        self._held = held

    def __call__(self, runner: Any) -> None:
        """After a tick: status changes, and a pose sample when one is due."""
        t = self._now(runner)
        self._last_time = t
        for index, code, reason in self.watcher.update():
            self.rec.status_events.append((t, index, code, reason))
        if t >= self._next_sample:
            self._sample(t)
        self._track_overlay(t)
        self._track_highlights(t)
        result = run_result(self.watcher)
        if result:
            self.rec.result = result

    # -- output -----------------------------------------------------------------------------
    def close(self) -> None:
        """Take the last frame and write the page (once). Problems are warnings."""
        if self._closed:
            return
        self._closed = True
        self._sample(self._last_time)
        from bt_manip.viz.replay_page import write_replay

        try:
            size = write_replay(self.path, self.rec, title=self.options.title)
        except OSError as exc:
            print(f"warning: cannot write the replay page {self.path}: {exc}", file=sys.stderr)
            return
        print(f"replay page: {self.path} ({size / 1e6:.1f} MB)")
