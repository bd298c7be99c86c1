"""Breakpoints and the ways they let go: unlock, disable, remove, lost heartbeat; and the
error replies for hook requests BT.CPP's publisher cannot survive (bt-manip answers them)."""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from typing import Any

import pytest
import zmq
from groot_client import GrootClient, sync_subscription

from bt_manip.bt import TreeContext, load_tree_string
from bt_manip.bt.status import NodeStatus
from bt_manip.clock import ManualClock
from bt_manip.groot import GrootPublisher, TreeMonitor

XML = """<root BTCPP_format="4"><BehaviorTree ID="Main">
  <Sequence><Script code="x:=1"/><Script name="second" code="x:=2"/></Sequence>
</BehaviorTree></root>"""
SECOND = 3


class Rig:
    def __init__(self, heartbeat: float = 5.0) -> None:
        self.tree = load_tree_string(XML, context=TreeContext(clock=ManualClock()))
        self.monitor = TreeMonitor(self.tree, self.tree.context.clock.now)
        self.publisher = GrootPublisher(self.monitor, port=0, max_heartbeat_delay=heartbeat)
        self.client = GrootClient(self.publisher.port)
        sync_subscription(self.client, self.publisher)
        self.result: dict[str, Any] = {}
        self.thread = threading.Thread(
            target=lambda: self.result.update(status=self.tree.tick()))

    def breakpoint(self, **extra: Any) -> None:
        hook = {"enabled": True, "uid": SECOND, "mode": 0, "once": False,
                "desired_status": "IDLE", "position": 0, **extra}
        assert len(self.client.request("I", json.dumps(hook))) == 1

    def tick_until_paused(self) -> None:
        self.thread.start()
        message = self.client.sub.recv_multipart()
        assert message[1] == str(SECOND).encode()
        assert self.publisher.paused_uid == SECOND
        assert self.tree.blackboard.get("x") == 1

    def close(self) -> None:
        self.publisher.close()
        if self.thread.is_alive():
            self.thread.join(10)
        self.client.close()
        self.monitor.close()


@pytest.fixture
def rig() -> Iterator[Rig]:
    r = Rig()
    yield r
    r.close()


@pytest.mark.parametrize("request_frames, ticked", [
    pytest.param(("U", {"uid": SECOND, "desired_status": "FAILURE", "position": 0,
                        "remove_when_done": False}), False, id="unlock with FAILURE"),
    pytest.param(("U", {"uid": SECOND, "desired_status": "IDLE", "position": 0,
                        "remove_when_done": True}), True, id="unlock and tick"),
    pytest.param(("X", None), True, id="disable all hooks"),
    pytest.param(("R", {"uid": SECOND, "position": 0}), True, id="remove the hook"),
    pytest.param(("A", None), True, id="remove all hooks"),
])
def test_a_paused_tree_goes_on_when_released(rig: Rig, request_frames: tuple[str, Any],
                                             ticked: bool) -> None:
    rig.breakpoint()
    rig.tick_until_paused()
    kind, body = request_frames
    reply = rig.client.request(kind, *(() if body is None else (json.dumps(body),)))
    assert reply[0][6:] == rig.publisher.uuid
    rig.thread.join(10)
    assert rig.result["status"] is (NodeStatus.SUCCESS if ticked else NodeStatus.FAILURE)
    assert rig.tree.blackboard.get("x") == (2 if ticked else 1)
    assert rig.publisher.paused_uid is None


def test_lost_heartbeat_disables_hooks_and_a_request_enables_them() -> None:
    rig = Rig(heartbeat=0.3)
    try:
        rig.breakpoint()
        rig.tick_until_paused()
        rig.thread.join(30)  # no request for 0.3 s: hooks are disabled, the tree goes on
        assert rig.result["status"] is NodeStatus.SUCCESS
        assert rig.tree.blackboard.get("x") == 2
        dump = json.loads(rig.client.request("D")[1])
        assert dump[0]["uid"] == SECOND  # the hook stays, enabled again by this request
        assert dump[0]["enabled"] is True
    finally:
        rig.close()


def test_updating_a_breakpoint_into_a_replace_hook_releases_it(rig: Rig) -> None:
    rig.breakpoint()
    rig.tick_until_paused()
    rig.breakpoint(mode=1, desired_status="SUCCESS")
    rig.thread.join(10)
    assert rig.result["status"] is NodeStatus.SUCCESS
    assert rig.tree.blackboard.get("x") == 1  # replaced: 'second' did not run


@pytest.mark.parametrize("kind, body, message", [
    ("I", "{not json", "hook is not valid JSON: "),
    ("I", '{"uid": 3}', "bad hook: hook without 'enabled'"),
    ("I", '{"enabled": true, "uid": 3, "mode": 7, "once": false, "desired_status": "IDLE", '
          '"position": 0}', "bad hook: hook mode must be 0 (breakpoint) or 1 (replace), got 7"),
    ("I", '{"enabled": true, "uid": 3, "mode": 0, "once": false, "desired_status": "DONE", '
          '"position": 0}', "bad hook: desired_status: expected one of SUCCESS"),
    ("U", '{"uid": 3}', "request without 'desired_status', 'position', 'remove_when_done'"),
    ("R", "[1]", "request must be a JSON object"),
    ("R", '{"uid": "3", "position": 0}', "'uid' must be an integer, got '3'"),
])
def test_malformed_hook_requests_get_an_error_reply(rig: Rig, kind: str, body: str,
                                                   message: str) -> None:
    reply = rig.client.request(kind, body)
    assert reply[0] == b"error"
    assert reply[1].decode().startswith(message)
    assert json.loads(rig.client.request("D")[1]) == []


def test_a_request_past_the_size_limit_drops_its_client_and_the_server_goes_on(
        rig: Rig) -> None:
    from bt_manip.groot.publisher import MAX_REQUEST_BYTES

    huge = GrootClient(rig.publisher.port, timeout_ms=500)
    try:
        with pytest.raises(zmq.Again):  # no reply: ZMQ dropped the connection
            huge.request("B", b"x" * (MAX_REQUEST_BYTES + 1))
    finally:
        huge.close()
    assert json.loads(rig.client.request("D")[1]) == []  # the server still answers
    names = rig.client.request("B", b"x" * 1000)  # within the limit: answered
    assert len(names) == 2


def test_a_closed_monitor_gives_the_nodes_their_own_classes_back() -> None:
    tree = load_tree_string(XML, context=TreeContext(clock=ManualClock()))
    classes = [type(node) for node in tree.nodes()]
    monitor = TreeMonitor(tree, tree.context.clock.now)
    seen: list[tuple[int, NodeStatus, NodeStatus]] = []
    monitor.consumers.append(lambda uid, old, new, _: seen.append((uid, old, new)))
    pairs = zip(tree.nodes(), classes, strict=True)
    assert all(isinstance(n, c) and type(n) is not c for n, c in pairs)
    assert tree.tick() is NodeStatus.SUCCESS
    assert seen[:3] == [(1, NodeStatus.IDLE, NodeStatus.RUNNING),
                        (2, NodeStatus.IDLE, NodeStatus.SUCCESS),
                        (3, NodeStatus.IDLE, NodeStatus.SUCCESS)]
    monitor.close()
    assert [type(node) for node in tree.nodes()] == classes
    assert tree.tick() is NodeStatus.SUCCESS and len(seen) == 7
    assert tree.root.last_status is NodeStatus.SUCCESS
