"""The live view: the world in meshcat and the tree page, updated after every tick.

:class:`LiveViewer` is a run hook (:class:`~bt_manip.run.hooks.RunHook`: ``hook(runner)``
after each tick, ``close()`` when the run has ended; with ``keep_serving`` it shows the end of
the run and goes on serving until :meth:`LiveViewer.stop`).
On :meth:`LiveViewer.start` it starts a meshcat server (or attaches to ``zmq_url``), draws the
world as it is (:mod:`bt_manip.viz.scene`), listens to the World's announcements
(:mod:`bt_manip.sim.events`) and serves the tree page (:mod:`bt_manip.viz.tree_page`). After
each tick it draws the bodies added since (spawned models, a ``block`` fault's crates) and
deletes the removed ones, sends the poses that changed, the overlay items (planned paths,
target frames) that changed, highlights objects while a robot holds them, keeps the first
robot in the middle of the view (:mod:`bt_manip.viz.camera`), and publishes the tree's
statuses to the page.

The viewer only reads the simulation. If it cannot start, or the meshcat server stops
answering, it warns once and the run goes on headless with the same result.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from bt_manip.bt.status import STATUS_CODES, NodeStatus
from bt_manip.overlay import FrameItem, Overlay, run_overlay
from bt_manip.sim.events import Attached, BodyAdded, BodyRemoved, Detached, WorldEvent
from bt_manip.viz.camera import CameraView, live_camera
from bt_manip.viz.meshcat_link import MeshcatLink, ViewerUnavailable
from bt_manip.viz.overlay import item_json
from bt_manip.viz.scene import ROOT, Scene, SceneBody, build_scene, column_major, row_matrix
from bt_manip.viz.tree_page import DEFAULT_PORT, PageState, TreePageServer, reachable
from bt_manip.viz.tree_state import TreeWatcher, run_result

if TYPE_CHECKING:
    from bt_manip.run.runner import Runner

OVERLAY_ROOT = "/meshcat/bt_manip_overlay"
HIGHLIGHT_RGBA = (0.15, 0.95, 0.55, 1.0)
"""Colour of an object while a robot holds it."""
MAX_FAILURES = 12
FAILURE_CODE = STATUS_CODES[NodeStatus.FAILURE]
"""Recent failures listed on the page."""
POSE_EPS = 1e-5
"""Pose changes below this (m, or quaternion units) are not sent again."""
FOLLOW_EPS = 0.005
"""The view re-centres on the robot when it has moved this far (m)."""


@dataclass(frozen=True)
class LiveOptions:
    """Where the live view is served, how often it updates, and whether it outlives the run
    (frozen: change a copy with :func:`dataclasses.replace`)."""

    zmq_url: str | None = None
    """Attach to this meshcat server; None starts one."""
    port: int | None = DEFAULT_PORT
    """Port of the tree page (0: any free port; None: no tree page)."""
    bind: str = "127.0.0.1"
    """Address the tree page and a meshcat server started here listen on."""
    max_fps: float = 30.0
    """At most this many scene updates per wall-clock second (the page shows every tick)."""
    timeout: float = 3.0
    """Seconds to wait for a meshcat server to answer."""
    keep_serving: bool = False
    """Go on serving the end of the run after :meth:`LiveViewer.close` (``--keep-serving``),
    until :meth:`LiveViewer.stop`."""


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
        overlay: what to draw over the world (default: the overlay of the tree's run).
    """

    def __init__(self, world: Any, tree: Any, options: LiveOptions | None = None,
                 title: str = "bt-manip", say: Callable[[str], None] = print,
                 overlay: Overlay | None = None) -> None:
        self.world = world
        self.tree = tree
        self.overlay = overlay if overlay is not None else run_overlay(tree)
        self.options = options or LiveOptions()
        self.title = title
        self.say = say
        self.link: MeshcatLink | None = None
        self.page: TreePageServer | None = None
        self.state = PageState(title=title)
        self.watcher = TreeWatcher(tree)
        self.scene: Scene | None = None
        self.camera: CameraView | None = None
        self._sent: dict[str, np.ndarray] = {}
        self._pending: list[tuple[str, Any]] = []
        self._unsubscribe: Callable[[], None] | None = None
        self._centre: np.ndarray | None = None
        self._overlay_version = -1
        self._overlay_items: dict[str, Any] = {}
        self._last_publish = 0.0
        self._failures: list[tuple[float, int, str]] = []
        self.updates = 0

    @property
    def active(self) -> bool:
        return self.link is not None

    def start(self) -> bool:
        """Start the viewer; if meshcat cannot run, warn once and return False (the run goes
        on headless).

        Raises :class:`~bt_manip.viz.tree_page.PortUnavailable` when the tree page cannot
        listen on its port (nothing is left running then).
        """
        if self.options.port is not None:
            self.state.nodes = self.watcher.structure()
            self.state.config = {"meshcat_url": "", "poll_ms": 200}
            self._publish_state()
            self.page = TreePageServer(self.state, port=self.options.port, host=self.options.bind)
        try:
            self.link = MeshcatLink(
                self.options.zmq_url, timeout=self.options.timeout, host=self.options.bind
            )
            self._draw_world()
            self.link.settle()
        except ViewerUnavailable as exc:
            self._drop(str(exc))
            self.stop()
            return False
        self.say(f"meshcat view: {reachable(self.link.web_url)}")
        if self.page is not None:
            self.state.config = {"meshcat_url": self.link.web_url, "poll_ms": 200}
            self.say(f"tree page: {self.page.url}")
        return True

    def _draw_world(self) -> None:
        link = self.link
        assert link is not None
        link.delete(ROOT)
        link.delete(OVERLAY_ROOT)
        if self.world is None:
            return
        self.scene = build_scene(self.world)
        self._send_bodies(list(self.scene.bodies.values()))
        self._unsubscribe = self.world.events.subscribe(self._on_world_event)
        # meshcat's orbit controls always look at the world origin: shift the drawing (and the
        # floor grid) so that the middle of the first robot sits there, and put the camera
        # behind and above it
        self.camera = live_camera(self.world)
        self._follow(force=True)
        down = np.eye(4)  # the nodes holding meshcat's floor grid (already turned) and axes
        down[2, 3] = -self.camera.target[2]
        link.set_transform("/Grid", column_major(down))
        link.set_transform("/Axes", column_major(down))
        d = self.camera.offset
        link.set_property("/Cameras/default/rotated/<object>", "position", [d[0], d[2], -d[1]])

    def _send_bodies(self, bodies: list[SceneBody]) -> None:
        """Draw bodies (their objects, static placements and current poses)."""
        link, scene = self.link, self.scene
        assert link is not None and scene is not None
        objects = [o for b in bodies for o in b.objects]
        data = {path: path.read_bytes() for path in {o.mesh for o in objects if o.mesh}}
        link.send_many(
            [{"type": "set_object", "path": o.path, "object": scene.lowered(o, data)}
             for o in objects]
            + [{"type": "set_transform", "path": path, "matrix": column_major(matrix)}
               for b in bodies for path, matrix in b.static]
        )
        moving = [b for b in bodies if b.tracks]
        for body in moving:
            for path in body.tracks:
                self._sent.pop(path, None)
        self._send_poses(moving)

    def _on_world_event(self, event: WorldEvent) -> None:
        """Listener of the World: note the change now (a new body is read from PyBullet while
        it exists), send it after the tick."""
        scene = self.scene
        if scene is None:
            return
        if isinstance(event, BodyAdded):
            self._pending.append(("add", scene.add_body(self.world, event)))
        elif isinstance(event, BodyRemoved):
            body = scene.remove_body(event.name)
            if body is not None:
                self._pending.append(("remove", body))
        elif isinstance(event, Attached | Detached):
            self._pending.append(("held" if isinstance(event, Attached) else "let go",
                                  event.object_name))

    def _take_events(self) -> None:
        """Draw the bodies added since the last tick, delete the removed ones, highlight what
        is held."""
        scene, link = self.scene, self.link
        if not self._pending or scene is None or link is None:
            return
        pending, self._pending[:] = list(self._pending), []
        for change, what in pending:
            if change == "add":
                body = scene.bodies.get(what.name)
                if body is not None and body is what:  # still there (not gone in the tick)
                    self._send_bodies([body])
            elif change == "remove":
                link.delete(what.path)
                for path in what.tracks:
                    self._sent.pop(path, None)
            else:
                self._set_highlight(what, change == "held")

    def _follow(self, force: bool = False) -> None:
        """Keep the first robot in the middle of the view (the drawing moves under the
        camera, since meshcat's orbit controls look at the origin)."""
        link, camera, scene = self.link, self.camera, self.scene
        if link is None or camera is None:
            return
        centre = np.array(camera.target[:2])
        body = scene.bodies.get(camera.follow.rsplit("/", 1)[-1]) if scene else None
        if body is not None and body.frames is not None:
            centre = np.array(body.read_poses(scene.client)[0][:2])  # type: ignore[union-attr]
        if not force and self._centre is not None and (
            np.abs(centre - self._centre).max() < FOLLOW_EPS
        ):
            return
        self._centre = centre
        shift = np.eye(4)
        shift[:3, 3] = (-centre[0], -centre[1], -camera.target[2])
        link.set_transform("/meshcat", column_major(shift))

    def _send_poses(self, bodies: list[SceneBody] | None = None) -> None:
        scene, link = self.scene, self.link
        if scene is None or link is None:
            return
        commands = []
        for body in bodies if bodies is not None else list(scene.bodies.values()):
            if not body.tracks:
                continue
            for path, row in zip(body.tracks, body.read_poses(scene.client), strict=True):
                sent = self._sent.get(path)
                if sent is not None and np.abs(row - sent).max() <= POSE_EPS:
                    continue
                self._sent[path] = row
                commands.append({"type": "set_transform", "path": path,
                                 "matrix": column_major(row_matrix(row))})
        link.send_many(commands)

    def _send_overlay(self) -> None:
        link = self.link
        overlay = self.overlay
        if link is None or overlay is None or overlay.version == self._overlay_version:
            return
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

    def _set_highlight(self, name: str, on: bool) -> None:
        link, scene = self.link, self.scene
        if link is None or scene is None or name not in scene.bodies:
            return
        for obj in scene.bodies[name].objects:
            if obj.rgba is not None:
                link.set_property(obj.path, "color", list(HIGHLIGHT_RGBA if on else obj.rgba))

    def _publish_state(self, runner: Runner | None = None) -> None:
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

    def __call__(self, runner: Runner) -> None:
        """After a tick: statuses to the page, poses/overlays/highlights to meshcat."""
        t = float(getattr(runner, "sim_time", 0.0))
        for index, code, reason in self.watcher.update():
            if code == FAILURE_CODE:
                self._failures.append((round(t, 4), index, reason))
        del self._failures[:-MAX_FAILURES]
        self._publish_state(runner)
        if self.link is None:
            return
        try:
            self._take_events()
            now = time.perf_counter()
            if now - self._last_publish < 1.0 / self.options.max_fps:
                return
            self._last_publish = now
            self._send_poses()
            self._send_overlay()
            self._follow()
            self.updates += 1
        except ViewerUnavailable as exc:
            self._drop(str(exc))

    def show_last(self) -> None:
        """Send what changed since the last update (the run's end state)."""
        if self.link is None or (self.world is not None and self.world.client < 0):
            return
        try:
            self._take_events()
            self._send_poses()
            self._send_overlay()
            self._follow()
        except ViewerUnavailable as exc:
            self._drop(str(exc))

    def close(self) -> None:
        """The run has ended: show the last poses, then :meth:`stop`, unless the options say
        to keep serving (``keep_serving``; :meth:`stop` ends it later). Idempotent."""
        self.show_last()
        if not self.options.keep_serving:
            self.stop()

    def stop(self) -> None:
        """Stop serving and disconnect (stops the meshcat server this viewer started).
        Idempotent."""
        if self._unsubscribe is not None:
            self._unsubscribe()
            self._unsubscribe = None
        if self.page is not None:
            self.page.close()
            self.page = None
        if self.link is not None:
            self.link.close()
            self.link = None
