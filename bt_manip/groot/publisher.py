"""The Groot2 publisher: serves a running tree to Groot2 over ZMQ, as BT.CPP's Groot2Publisher.

A REP socket on ``PORT`` answers Groot2's requests from a thread of its own, so it keeps
answering while the tree is paused on a breakpoint; a PUB socket on ``PORT + 1`` announces the
breakpoints reached. Both bind ``127.0.0.1`` unless another address is given. Every request is
a heartbeat: after ``max_heartbeat_delay`` seconds without one, every hook is disabled (a
paused tree goes on), and re-enabled when Groot2 comes back.

A breakpoint blocks the thread that ticks the tree, inside the tick: the runner neither steps
physics nor advances the sim clock until Groot2 unlocks it.
"""

from __future__ import annotations

import json
import os
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

import msgpack
import zmq

from bt_manip.bt.node import BtNode
from bt_manip.bt.status import STATUS_CODES, NodeStatus
from bt_manip.groot import hooks as hk
from bt_manip.groot.layout import registered_classes, tree_xml
from bt_manip.groot.monitor import TreeMonitor
from bt_manip.groot.protocol import (
    RequestType,
    encode_transitions,
    parse_request_header,
    random_tree_uuid,
    reply_header,
    request_header,
    status_code,
)

if TYPE_CHECKING:
    from bt_manip.run.runner import Runner

DEFAULT_GROOT_PORT = 1667
MAX_TRANSITIONS = 1000
MAX_REQUEST_BYTES = 1024 * 1024
"""Largest request frame the server takes (Groot2's are a few hundred bytes: a hook in JSON,
blackboard names); ZMQ drops the connection of a client that sends a larger one."""
_TWO_PARTS = (RequestType.BLACKBOARD, RequestType.HOOK_INSERT, RequestType.HOOK_REMOVE,
              RequestType.BREAKPOINT_UNLOCK, RequestType.TOGGLE_RECORDING)


class GrootError(RuntimeError):
    """The publisher cannot start (a port in use, a bad address)."""


class GrootPublisher:
    """Serves ``monitor``'s tree to Groot2 until :meth:`close`.

    A run hook (:class:`~bt_manip.run.hooks.RunHook`): the status changes come from the
    monitor, so there is nothing to do after a tick; the runner closes it when the run ends.

    Args:
        monitor: the tree's status-change monitor (its clock stamps the transitions).
        port: REP port (PUB on ``port + 1``); 0 picks a free pair of ports.
        bind: address to listen on.
        max_heartbeat_delay: seconds without a request after which hooks are disabled.
        on_pause: called with the node's UID when a breakpoint pauses the tree, and with None
            when it goes on (the console uses it to tell the user).
    """

    def __init__(
        self,
        monitor: TreeMonitor,
        port: int = DEFAULT_GROOT_PORT,
        bind: str = "127.0.0.1",
        max_heartbeat_delay: float = 5.0,
        xml: str | None = None,
        on_pause: Callable[[int | None], None] | None = None,
    ) -> None:
        self.monitor = monitor
        self.layout = monitor.layout
        self.xml = xml if xml is not None else tree_xml(self.layout, registered_classes())
        self.max_heartbeat_delay = max_heartbeat_delay
        self.on_pause = on_pause
        self.uuid = random_tree_uuid()
        self._context = zmq.Context()
        self._server = self._context.socket(zmq.REP)
        self._pub = self._context.socket(zmq.PUB)
        for sock in (self._server, self._pub):
            sock.setsockopt(zmq.LINGER, 0)
            sock.setsockopt(zmq.RCVTIMEO, 100)
            sock.setsockopt(zmq.SNDTIMEO, 1000)
        self._server.setsockopt(zmq.MAXMSGSIZE, MAX_REQUEST_BYTES)
        try:
            self.port = self._bind(bind, port)
        except BaseException:
            self._close_sockets()
            raise
        self.bind = bind
        order = self.layout.status_order()
        self._status = bytearray()
        self._status_at: dict[int, int] = {}
        for uid in order:
            self._status += uid.to_bytes(2, "little")
            self._status_at[uid] = len(self._status)
            self._status.append(0)
        self._recording = False
        self._recording_start = 0
        self._transitions: deque[tuple[int, int, int]] = deque(maxlen=MAX_TRANSITIONS)
        self._hooks: dict[int, hk.Hook] = {}
        self._cond = threading.Condition()
        self._last_heartbeat = time.monotonic()
        self._has_heartbeat = True
        self.paused_uid: int | None = None
        """UID of the node whose breakpoint holds the tree now (None when it runs)."""
        self._active = True
        self._closed = False
        monitor.consumers.append(self._record)
        self._thread = threading.Thread(target=self._serve, name="groot2-publisher", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ sockets

    def _bind(self, address: str, port: int) -> int:
        if port != 0:
            self._bind_one(self._server, address, port)
            self._bind_one(self._pub, address, port + 1)
            return port
        for _ in range(50):
            try:
                chosen = self._server.bind_to_random_port(f"tcp://{address}", 20000, 60000)
            except zmq.ZMQError as e:
                raise GrootError(f"cannot listen on {address}: {e}") from None
            try:
                self._pub.bind(f"tcp://{address}:{chosen + 1}")
                return chosen
            except zmq.ZMQError:
                self._server.unbind(self._server.getsockopt_string(zmq.LAST_ENDPOINT))
        raise GrootError("no free pair of ports found")

    @staticmethod
    def _bind_one(sock: zmq.Socket, address: str, port: int) -> None:
        try:
            sock.bind(f"tcp://{address}:{port}")
        except zmq.ZMQError as e:
            raise GrootError(f"cannot listen on {address}:{port}: {e}") from None

    def _close_sockets(self) -> None:
        self._server.close(0)
        self._pub.close(0)
        self._context.term()

    def __call__(self, runner: Runner) -> None:
        """After a tick: nothing (the monitor has passed on every change already)."""

    def close(self) -> None:
        """Stop serving: hooks are removed (a paused tree goes on), the thread ends.
        Idempotent."""
        if self._closed:
            return
        self._closed = True
        self.remove_all_hooks()
        self._active = False
        self._thread.join()
        with self.monitor.lock:
            if self._record in self.monitor.consumers:
                self.monitor.consumers.remove(self._record)
        self._close_sockets()

    # ------------------------------------------------------------------ status changes

    def _record(self, uid: int, previous: NodeStatus, new: NodeStatus, stamp: int) -> None:
        """Runs under the monitor's lock at each status change."""
        at = self._status_at.get(uid)
        if at is not None:
            self._status[at] = status_code(previous, new)
        if self._recording:
            self._transitions.append((stamp - self._recording_start, uid, STATUS_CODES[new]))

    # ------------------------------------------------------------------ serving

    def _serve(self) -> None:
        while self._active:
            try:
                frames = self._server.recv_multipart()
            except zmq.Again:
                self._check_heartbeat()
                continue
            except zmq.ZMQError:
                break
            self._last_heartbeat = time.monotonic()
            self._check_heartbeat()
            try:
                reply = self.handle(frames)
            except Exception as e:  # a request that breaks a handler still gets an answer
                reply = _error(f"request failed: {e}")
            try:
                self._server.send_multipart(reply)
            except zmq.ZMQError:
                continue

    def _check_heartbeat(self) -> None:
        alive = time.monotonic() - self._last_heartbeat < self.max_heartbeat_delay
        if alive != self._has_heartbeat:
            self._has_heartbeat = alive
            self.enable_all_hooks(alive)

    def handle(self, frames: list[bytes]) -> list[bytes]:
        """The reply frames to one request."""
        header = parse_request_header(frames[0]) if frames else None
        if header is None:
            return _error("wrong request header")
        _, kind, request_id = header
        if kind not in RequestType._value2member_map_ or kind == RequestType.BREAKPOINT_REACHED:
            return _error("Request not recognized")
        kind = RequestType(kind)
        if kind in _TWO_PARTS and len(frames) != 2:
            return _error("must be 2 parts message")
        reply = [reply_header(kind, request_id, self.uuid)]
        payload = frames[1] if len(frames) > 1 else b""
        if kind is RequestType.FULLTREE:
            reply.append(self.xml.encode())
        elif kind is RequestType.STATUS:
            with self.monitor.lock:
                reply.append(bytes(self._status))
        elif kind is RequestType.BLACKBOARD:
            reply.append(self.blackboards_dump(payload.decode(errors="replace")))
        elif kind is RequestType.HOOK_INSERT:
            problem = self._insert_hooks(payload)
            if problem:
                return _error(problem)
        elif kind is RequestType.HOOK_REMOVE:
            return self._remove_request(payload) or reply
        elif kind is RequestType.BREAKPOINT_UNLOCK:
            return self._unlock_request(payload) or reply
        elif kind is RequestType.REMOVE_ALL_HOOKS:
            self.remove_all_hooks()
        elif kind is RequestType.DISABLE_ALL_HOOKS:
            self.enable_all_hooks(False)
        elif kind is RequestType.HOOKS_DUMP:
            with self._cond:
                dump = [hook.to_json() for hook in self._hooks.values()]
            reply.append(json.dumps(dump, separators=(",", ":"), sort_keys=True).encode())
        elif kind is RequestType.TOGGLE_RECORDING:
            command = payload.decode(errors="replace")
            if command == "start":
                with self.monitor.lock:
                    self._recording_start = self.monitor.time_us()
                    self._transitions.clear()
                    self._recording = True
                reply.append(str(time.time_ns() // 1000).encode())
            elif command == "stop":
                self._recording = False
        elif kind is RequestType.GET_TRANSITIONS:
            with self.monitor.lock:
                data = encode_transitions(self._transitions)
                self._transitions.clear()
            reply.append(data)
        return reply

    # ------------------------------------------------------------------ blackboards

    def blackboards_dump(self, names: str) -> bytes:
        """msgpack of ``{instance: {key: value}}`` for the instances named in ``a;b;c``."""
        out: dict[str, Any] = {}
        for name in names.split(";"):
            inst = self.layout.instance(name)
            if inst is None:
                continue
            for _ in range(5):  # the tree's thread may write while we read
                try:
                    entries = inst.blackboard.as_dict()
                    break
                except RuntimeError:
                    continue
            else:
                entries = {}
            out[name] = entries or None
        return cast(bytes, msgpack.packb(out))

    # ------------------------------------------------------------------ hooks

    def _insert_hooks(self, payload: bytes) -> str:
        try:
            data = json.loads(payload)
        except ValueError as e:
            return f"hook is not valid JSON: {e}"
        items = data if isinstance(data, list) else [data]
        try:
            for item in items:
                self.insert_hook(item)
        except hk.HookError as e:
            return f"bad hook: {e}"
        return ""

    def insert_hook(self, data: dict[str, Any]) -> bool:
        """Add or update the hook described by a HOOK_INSERT JSON object; False when no node
        has its UID (BT.CPP ignores such a hook too)."""
        probe = hk.Hook(0)
        probe.update(data)
        with self._cond:
            hook = self._hooks.get(probe.uid) if probe.position == hk.PRE else None
            if hook is not None:
                was_breakpoint = hook.mode == hk.BREAKPOINT
                hook.update(data)
                if was_breakpoint and hook.mode == hk.REPLACE:
                    hook.ready = True
                    self._cond.notify_all()
                return True
            node = self.layout.nodes_by_uid.get(probe.uid)
            if node is None:
                return False
            self._hooks[probe.uid] = probe
            node.pre_tick = self._pre_tick
        return True

    def _json_request(self, payload: bytes, keys: tuple[str, ...]) -> dict[str, Any] | str:
        try:
            data = json.loads(payload)
        except ValueError as e:
            return f"request is not valid JSON: {e}"
        if not isinstance(data, dict):
            return "request must be a JSON object"
        missing = [k for k in keys if k not in data]
        if missing:
            return "request without " + ", ".join(f"'{k}'" for k in missing)
        if not isinstance(data["uid"], int) or isinstance(data["uid"], bool):
            return f"'uid' must be an integer, got {data['uid']!r}"
        return data

    def _remove_request(self, payload: bytes) -> list[bytes] | None:
        data = self._json_request(payload, ("uid", "position"))
        if isinstance(data, str):
            return _error(data)
        if not self.remove_hook(data["position"], data["uid"]):
            return _error("Node ID not found")
        return None

    def _unlock_request(self, payload: bytes) -> list[bytes] | None:
        data = self._json_request(
            payload, ("uid", "desired_status", "position", "remove_when_done"))
        if isinstance(data, str):
            return _error(data)
        status = hk.unlock_status(data["desired_status"])
        if not self.unlock(data["position"], data["uid"], status, bool(data["remove_when_done"])):
            return _error("Node ID not found")
        return None

    def unlock(self, position: int, uid: int, status: NodeStatus, remove: bool) -> bool:
        """Let a breakpoint go on with ``status`` (SUCCESS/FAILURE replace the node's tick)."""
        with self._cond:
            hook = self._hooks.get(uid) if position == hk.PRE else None
            if hook is None:
                return False
            hook.desired_status = status
            hook.remove_when_done = hook.remove_when_done or remove
            if hook.mode == hk.BREAKPOINT:
                hook.ready = True
                self._cond.notify_all()
        return True

    def remove_hook(self, position: int, uid: int) -> bool:
        with self._cond:
            hook = self._hooks.get(uid) if position == hk.PRE else None
            if hook is None:
                return False
            del self._hooks[uid]
            self.layout.nodes_by_uid[uid].pre_tick = None
            if hook.mode == hk.BREAKPOINT:
                hook.enabled = False
                self._cond.notify_all()
        return True

    def remove_all_hooks(self) -> None:
        with self._cond:
            uids = list(self._hooks)
        for uid in uids:
            self.remove_hook(hk.PRE, uid)

    def enable_all_hooks(self, enable: bool) -> None:
        with self._cond:
            for hook in self._hooks.values():
                hook.enabled = enable
            self._cond.notify_all()

    def hooks(self) -> list[hk.Hook]:
        with self._cond:
            return list(self._hooks.values())

    def _pre_tick(self, node: BtNode) -> NodeStatus:
        """Runs on the tree's thread before the tick of a node that has a hook."""
        uid = self.layout.uid_of.get(id(node))
        with self._cond:
            hook = self._hooks.get(uid) if uid is not None else None
            if hook is None or not hook.enabled:
                return NodeStatus.SKIPPED
            breakpoint = hook.mode == hk.BREAKPOINT
            if breakpoint:
                self.paused_uid = uid
                if self.on_pause is not None:
                    self.on_pause(uid)
            notice = request_header(RequestType.BREAKPOINT_REACHED,
                                    int.from_bytes(os.urandom(4), "little"))
            self._pub.send_multipart([notice, str(uid).encode()])
            if breakpoint:
                try:
                    while not (hook.ready or not hook.enabled):
                        self._cond.wait(0.2)  # short waits: Ctrl-C still interrupts
                finally:
                    hook.ready = False
                    self.paused_uid = None
                    if self.on_pause is not None:
                        self.on_pause(None)
                if not hook.enabled:
                    return NodeStatus.SKIPPED
            if hook.remove_when_done:
                self._hooks.pop(hook.uid, None)
                node.pre_tick = None
            return hook.desired_status


def _error(message: str) -> list[bytes]:
    return [b"error", message.encode()]
