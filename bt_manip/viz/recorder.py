"""Record a run for the replay page: the bodies as they come and go, poses at a fixed rate,
tree status changes.

:class:`Recorder` is a run hook (:class:`~bt_manip.run.hooks.RunHook`). On creation it draws
the world as it is (:mod:`bt_manip.viz.scene`), takes a first frame at the current sim time and
listens to the World's announcements (:mod:`bt_manip.sim.events`): a body added later (a spawned
model, a ``block`` fault's crate) is drawn from then on, a removed one is hidden from then on
(each body keeps its appear and disappear times), and an attached object is highlighted while
held. After every tick it

- records each node whose status or reason changed (exact tick time),
- samples every moving frame when ``1 / sample_hz`` of sim time has passed since the last
  sample (and always on the last tick, and when a body has just appeared),
- records overlay items (planned paths, target frames) that changed.

:meth:`Recorder.close` writes the self-contained page (:mod:`bt_manip.viz.replay_page`). The
recorder only reads the simulation, so a recorded run ends exactly like an unrecorded one.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from bt_manip.bt.walk import walk_nodes
from bt_manip.overlay import FrameItem, Overlay, run_overlay
from bt_manip.run.node_counts import COUNT_FIELDS, NodeCounter
from bt_manip.sim.events import Attached, BodyAdded, BodyRemoved, Detached, WorldEvent
from bt_manip.viz.camera import replay_camera
from bt_manip.viz.overlay import item_json
from bt_manip.viz.recording import RecordedBody, Recording
from bt_manip.viz.replay_page import write_replay
from bt_manip.viz.scene import ROOT, Scene
from bt_manip.viz.tree_state import TreeWatcher, run_result

if TYPE_CHECKING:
    from bt_manip.run.runner import Runner

__all__ = ["RecordOptions", "RecordedBody", "Recorder", "Recording"]


@dataclass(frozen=True)
class RecordOptions:
    """How densely to sample the run, and the page's title (frozen: change a copy with
    :func:`dataclasses.replace`)."""

    sample_hz: float = 20.0
    """Pose samples per second of sim time (ticks between samples are not drawn)."""
    title: str = ""


class Recorder:
    """A run hook that records the run and writes a replay page on :meth:`close`.

    Args:
        path: the HTML file to write.
        world: the loaded World, or None (tree statuses only).
        tree: the tree (``root``, optional ``node_records()``).
        options: sampling rate and page title.
        overlay: what is drawn over the world (default: the overlay of the tree's run).
    """

    def __init__(self, path: str | Path, world: Any, tree: Any,
                 options: RecordOptions | None = None, info: dict[str, Any] | None = None,
                 overlay: Overlay | None = None) -> None:
        self.path = Path(path)
        self.world = world
        self.overlay = overlay if overlay is not None else run_overlay(tree)
        self.options = options or RecordOptions()
        self.watcher = TreeWatcher(tree)
        details = dict(info or {})
        if world is not None:
            details.setdefault("robots", list(getattr(world, "robots", {}) or {}))
        self.rec = Recording([], self.watcher.structure(), info=details)
        self._t0 = float(world.time) if world is not None else 0.0
        self._scene: Scene | None = None
        self._present: dict[str, RecordedBody] = {}
        self._keys: dict[str, int] = {}
        self._appeared = False
        self._unsubscribe: Callable[[], None] | None = None
        self._next_sample = 0.0
        self._overlay_version = -1
        self._overlay_items: dict[str, Any] = {}
        self._last_time = 0.0
        self._closed = False
        self._counter: NodeCounter | None = None
        self._paths = [w.path for w in walk_nodes(tree.root)]
        if world is not None:
            self._scene = Scene(client=world.client)
            for info_ in world.infos.values():
                if info_.kind != "ground":
                    self._add_body(world, info_, 0.0)
            self._unsubscribe = world.events.subscribe(self._on_world_event)
        self._sample(0.0)
        self._track_overlay(0.0)

    # -- bodies ------------------------------------------------------------------------------
    def _add_body(self, world: Any, info: Any, t: float) -> None:
        assert self._scene is not None
        n = self._keys.get(info.name, 0) + 1
        self._keys[info.name] = n
        key = info.name if n == 1 else f"{info.name}~{n}"
        drawing = self._scene.add_body(world, info, path=f"{ROOT}/{key}")
        body = RecordedBody(key, drawing, appear=t, first_frame=len(self.rec.times))
        if drawing.tracks and self.rec.times and self.rec.times[-1] >= t:
            # it is there in the frame already taken at this time
            body.first_frame = len(self.rec.times) - 1
            body.samples.append(drawing.read_poses(self._scene.client).astype(np.float32))
        self.rec.bodies.append(body)
        self._present[info.name] = body

    def _on_world_event(self, event: WorldEvent) -> None:
        """Listener of the World: a body is drawn when it appears (read from PyBullet while
        it exists) and stops being sampled when it is removed."""
        t = float(event.time) - self._t0
        if isinstance(event, BodyAdded):
            self._add_body(self.world, event, t)
            self._appeared = True
        elif isinstance(event, BodyRemoved):
            body = self._present.pop(event.name, None)
            if body is not None:
                body.disappear = t
                assert self._scene is not None
                self._scene.remove_body(event.name)
        elif isinstance(event, Attached | Detached):
            body = self._present.get(event.object_name)
            if body is not None:
                self.rec.highlight_events.append((t, body.key, isinstance(event, Attached)))

    # -- sampling ---------------------------------------------------------------------------
    def _now(self, runner: Runner) -> float:
        if self.world is not None:
            return float(self.world.time) - self._t0
        return float(getattr(runner, "sim_time", 0.0))

    def _sample(self, t: float) -> None:
        if self.rec.times and t <= self.rec.times[-1]:
            return
        self.rec.times.append(t)
        if self._scene is not None:
            for body in self._present.values():
                if body.drawing.tracks:
                    poses = body.drawing.read_poses(self._scene.client)
                    body.samples.append(poses.astype(np.float32))
        self._next_sample = t + 1.0 / self.options.sample_hz - 1e-9

    def _track_overlay(self, t: float) -> None:
        overlay = self.overlay
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

    def __call__(self, runner: Runner) -> None:
        """After a tick: bodies added or removed, status changes, and a pose sample when one
        is due (or a body just appeared)."""
        t = self._now(runner)
        self._last_time = t
        self._counter = getattr(runner, "counter", None)
        for index, code, reason in self.watcher.update():
            self.rec.status_events.append((t, index, code, reason))
        if t >= self._next_sample or self._appeared:
            self._appeared = False
            self._sample(t)
        self._track_overlay(t)
        result = run_result(self.watcher)
        if result:
            self.rec.result = result

    # -- output -----------------------------------------------------------------------------
    def close(self) -> None:
        """Take the last frame and write the page (once). Problems are warnings."""
        if self._closed:
            return
        self._closed = True
        if self._unsubscribe is not None:
            self._unsubscribe()
        if self._counter is not None:  # the run's counts, each node's ticks and results
            self.rec.counts = [[self._counter.of(p)[k] for k in COUNT_FIELDS]
                               for p in self._paths]
        if self.world is None:
            self._sample(self._last_time)
        elif self.world.client >= 0:  # a closed world has no poses left to read
            self._sample(self._last_time)
            self.rec.info["camera"] = replay_camera(self.world, self.rec)
        try:
            size = write_replay(self.path, self.rec, title=self.options.title)
        except OSError as exc:
            print(f"warning: cannot write the replay page {self.path}: {exc}", file=sys.stderr)
            return
        print(f"replay page: {self.path} ({size / 1e6:.1f} MB)")
