"""The live view: the world in meshcat and the tree page, updated after every tick.

:class:`LiveViewer` is a run hook (``hook(runner)`` after each tick, ``close()`` at the end).
On :meth:`LiveViewer.start` it starts a meshcat server (or attaches to ``zmq_url``), draws the
world once (:mod:`bt_manip.viz.scene`) and serves the tree page (:mod:`bt_manip.viz.tree_page`).
After each tick it sends the poses that changed, the overlay items (planned paths, target
frames) that changed, highlights objects while a robot holds them, and publishes the tree's
statuses to the page.

The viewer only reads the simulation. If it cannot start, or the meshcat server stops
answering, it warns once and the run goes on headless with the same result.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from bt_manip.viz.meshcat_link import MeshcatLink, ViewerUnavailable
from bt_manip.viz.overlay import FrameItem
from bt_manip.viz.scene import ROOT, Scene, build_scene, column_major, pose_matrix
from bt_manip.viz.tree_page import DEFAULT_PORT, PageState, TreePageServer
from bt_manip.viz.tree_state import TreeWatcher, run_result

OVERLAY_ROOT = "/meshcat/bt_manip_overlay"
HIGHLIGHT_RGBA = (0.15, 0.95, 0.55, 1.0)
"""Colour of an object while a robot holds it."""
MAX_FAILURES = 12
"""Recent failures listed on the page."""
FAILURE = 3
POSE_EPS = 1e-5
"""Pose changes below this (m, or quaternion units) are not sent again."""


@dataclass
class LiveOptions:
    """Where the live view is served and how often it updates."""

    zmq_url: str | None = None
    """Attach to this meshcat server; None starts one."""
    port: int | None = DEFAULT_PORT
    """Port of the tree page on localhost (0: any free port; None: no tree page)."""
    max_fps: float = 30.0
    """At most this many scene updates per wall-clock second (the page shows every tick)."""
    timeout: float = 3.0


def camera_for(world: Any, scene: Scene) -> dict[str, list[float]]:
    """A first view: a few metres behind and above the first robot, or over the world."""
    target = np.zeros(3)
    if world is not None and getattr(world, "robots", None):
        name = next(iter(world.robots))
        path = f"{ROOT}/{name}"
        if path in scene.tracks:
            target = scene.read_poses()[scene.tracks.index(path)][:3].copy()
            target[2] = 0.5
    position = target + np.array([-2.6, -2.2, 2.0])
    return {"target": target.round(3).tolist(), "position": position.round(3).tolist()}


def _warn(message: str) -> None:
    print(f"warning: {message}; running without the live view", file=sys.stderr)


class LiveViewer:
    """Live meshcat view of a world plus the tree page; a run hook.

    Args:
        world: the loaded World, or None (tree page only, empty 3D view).
        tree: the tree (``root``, optional ``node_records()``).
        options: server, port and update rate.
        title: shown on the page (e.g. the tree file).
        say: where the URLs are printed.
    """

    def __init__(self, world: Any, tree: Any, options: LiveOptions | None = None,
                 title: str = "bt-manip", say: Callable[[str], None] = print) -> None:
        self.world = world
        self.tree = tree
        self.options = options or LiveOptions()
        self.title = title
        self.say = say
        self.link: MeshcatLink | None = None
        self.page: TreePageServer | None = None
        self.state = PageState(title=title)
        self.watcher = TreeWatcher(tree)
        self.scene: Scene | None = None
        self._sent: np.ndarray | None = None
        self._overlay_version = -1
        self._overlay_items: dict[str, Any] = {}
        self._held: set[str] = set()
        self._last_publish = 0.0
        self._failures: list[tuple[float, int, str]] = []
        self.updates = 0

    @property
    def active(self) -> bool:
        return self.link is not None

    def start(self) -> bool:
        """Start the viewer; on failure warn once and return False (the run goes on)."""
        try:
            self.link = MeshcatLink(self.options.zmq_url, timeout=self.options.timeout)
        except ViewerUnavailable as exc:
            _warn(str(exc))
            return False
        try:
            self._draw_world()
        except ViewerUnavailable as exc:
            self._drop(str(exc))
            return False
        self.say(f"meshcat view: {self.link.web_url}")
        if self.options.port is not None:
            self._start_page()
        return True

    def _start_page(self) -> None:
        assert self.link is not None
        self.state.nodes = self.watcher.structure()
        self.state.config = {"meshcat_url": self.link.web_url, "poll_ms": 200}
        self._publish_state()
        try:
            self.page = TreePageServer(self.state, port=self.options.port or 0)
        except OSError as exc:
            print(
                f"warning: cannot serve the tree page on port {self.options.port} ({exc}); "
                "the meshcat view still runs (choose another port with --port)",
                file=sys.stderr,
            )
            return
        self.say(f"tree page: {self.page.url}")

    def _draw_world(self) -> None:
        link = self.link
        assert link is not None
        link.delete(ROOT)
        link.delete(OVERLAY_ROOT)
        if self.world is None:
            return
        self.scene = build_scene(self.world)
        data = {path: path.read_bytes() for path in self.scene.mesh_files()}
        link.send_many(
            [
                {"type": "set_object", "path": o.path, "object": self.scene.lowered(o, data)}
                for o in self.scene.objects
            ]
            + [
                {"type": "set_transform", "path": path, "matrix": column_major(matrix)}
                for path, matrix in self.scene.static
            ]
        )
        self._send_poses(force=True)
        # meshcat's orbit controls always look at the world origin: shift the drawing so that
        # the first robot sits there, and put the camera behind and above it
        camera = camera_for(self.world, self.scene)
        target, position = np.array(camera["target"]), np.array(camera["position"])
        shift = np.eye(4)
        shift[:2, 3] = -target[:2]
        link.set_transform("/meshcat", column_major(shift))
        d = position - np.array([target[0], target[1], 0.0])
        link.set_property("/Cameras/default/rotated/<object>", "position", [d[0], d[2], -d[1]])

    def _send_poses(self, force: bool = False) -> None:
        scene, link = self.scene, self.link
        if scene is None or link is None or not scene.tracks:
            return
        poses = scene.read_poses()
        if self._sent is None or force:
            changed = np.arange(len(poses))
        else:
            changed = np.flatnonzero(np.abs(poses - self._sent).max(axis=1) > POSE_EPS)
        link.send_many(
            [
                {"type": "set_transform", "path": scene.tracks[k],
                 "matrix": column_major(pose_matrix(poses[k]))}
                for k in changed
            ]
        )
        if self._sent is None or force:
            self._sent = poses
        else:
            self._sent[changed] = poses[changed]

    def _send_overlay(self) -> None:
        link = self.link
        overlay = getattr(self.world, "overlay", None) if self.world is not None else None
        if link is None or overlay is None or overlay.version == self._overlay_version:
            return
        from bt_manip.viz.overlay import item_json

        self._overlay_version = overlay.version
        for name in list(self._overlay_items):
            if name not in overlay.items:
                link.delete(f"{OVERLAY_ROOT}/{name}")
                del self._overlay_items[name]
        for name, item in overlay.items.items():
            if self._overlay_items.get(name) is item:
                continue
            previous = self._overlay_items.get(name)
            if isinstance(item, FrameItem) and isinstance(previous, FrameItem) and (
                previous.size == item.size
            ):
                # same triad, new pose: move it
                link.set_transform(f"{OVERLAY_ROOT}/{name}", column_major(item.matrix))
            else:
                link.set_transform(f"{OVERLAY_ROOT}/{name}", column_major(np.eye(4)))
                obj = item_json(item)
                if isinstance(item, FrameItem):
                    obj["object"]["matrix"] = column_major(np.eye(4))
                    link.set_object(f"{OVERLAY_ROOT}/{name}", obj)
                    link.set_transform(f"{OVERLAY_ROOT}/{name}", column_major(item.matrix))
                else:
                    link.set_object(f"{OVERLAY_ROOT}/{name}", obj)
            self._overlay_items[name] = item

    def _send_highlights(self) -> None:
        link, scene = self.link, self.scene
        if link is None or scene is None:
            return
        held = held_objects(self.world)
        if held == self._held:
            return
        for name in held ^ self._held:
            on = name in held
            for k in scene.body_objects.get(name, []):
                obj = scene.objects[k]
                if obj.rgba is None:
                    continue
                rgba = HIGHLIGHT_RGBA if on else obj.rgba
                link.set_property(obj.path, "color", list(rgba))
        self._held = held

    def _publish_state(self, runner: Any = None) -> None:
        sim_time = float(getattr(runner, "sim_time", 0.0)) if runner is not None else 0.0
        ticks = int(getattr(runner, "ticks", 0)) if runner is not None else 0
        statuses = list(self.watcher.statuses)
        result = run_result(self.watcher)
        self.state.publish(sim_time, ticks, statuses, list(self.watcher.reasons), result,
                           self._failures)

    def _drop(self, reason: str) -> None:
        _warn(reason)
        if self.link is not None:
            self.link.close()
            self.link = None

    def __call__(self, runner: Any) -> None:
        """After a tick: statuses to the page, poses/overlays/highlights to meshcat."""
        t = float(getattr(runner, "sim_time", 0.0))
        for index, code, reason in self.watcher.update():
            if code == FAILURE:
                self._failures.append((round(t, 4), index, reason))
        del self._failures[:-MAX_FAILURES]
        self._publish_state(runner)
        if self.link is None:
            return
        now = time.perf_counter()
        if now - self._last_publish < 1.0 / self.options.max_fps:
            return
        self._last_publish = now
        try:
            self._send_poses()
            self._send_overlay()
            self._send_highlights()
            self.updates += 1
        except ViewerUnavailable as exc:
            self._drop(str(exc))

    def close(self) -> None:
        """Show the last poses, stop serving and disconnect (stops the meshcat server this
        viewer started)."""
        if self.link is not None:
            try:
                self._send_poses()
                self._send_overlay()
                self._send_highlights()
            except ViewerUnavailable:
                pass
        if self.page is not None:
            self.page.close()
            self.page = None
        if self.link is not None:
            self.link.close()
            self.link = None


def held_objects(world: Any) -> set[str]:
    """Names of the objects attached to a robot right now."""
    attachments = getattr(world, "attachments", None)
    if attachments is None:
        return set()
    try:
        return {a.object_name for a in attachments.all()}
    except Exception:
        return set()
