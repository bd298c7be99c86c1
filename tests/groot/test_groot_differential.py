"""bt-manip's Groot2 publisher and .btlog files against BehaviorTree.CPP 4.8.2's own
(``behaviortreepy``'s ``Groot2Publisher`` and ``FileLogger``), on the same XML and ticks.

A pyzmq client plays Groot2 and asks both publishers the same questions; the replies must
agree: headers (apart from the random tree UUID), FULLTREE node structure and UIDs, STATUS
bytes, BLACKBOARD content, hook dumps, recorded transitions and error replies.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import msgpack
import pytest
from groot_client import GrootClient, free_port_pair

from bt_manip.bt import TreeContext, load_tree_string
from bt_manip.bt.xml_parse import parse_xml_text
from bt_manip.clock import ManualClock
from bt_manip.groot import BtlogWriter, GrootPublisher, TreeMonitor, read_btlog

b = pytest.importorskip("behaviortreepy")

XML = """<root BTCPP_format="4" main_tree_to_execute="MainTree">
  <BehaviorTree ID="MainTree">
    <Sequence name="top">
      <Script code="a:=42; s:='hi'; d:=1.5" _skipIf="false"/>
      <SubTree ID="Pick" name="pick_one" x="{a}"/>
      <SubTree ID="Pick" _autoremap="true"/>
      <Repeat num_cycles="2"><AlwaysSuccess/></Repeat>
      <Fallback><AlwaysFailure/><Inverter><AlwaysFailure/></Inverter></Fallback>
      <SequenceWithMemory><AlwaysSuccess/><Script code="n:=n+1"/></SequenceWithMemory>
      <ReactiveSequence>
        <Script code="flag:=true"/>
        <KeepRunningUntilFailure><Precondition if="n&lt;3" else="FAILURE">
          <AlwaysSuccess/></Precondition></KeepRunningUntilFailure>
      </ReactiveSequence>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Pick">
    <Sequence><Script code="local:=7"/><SubTree ID="Grasp"/></Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Grasp">
    <ForceSuccess><AlwaysFailure name="close"/></ForceSuccess>
  </BehaviorTree>
</root>"""
TICKS = 3


class Reference:
    """BT.CPP's tree with its Groot2 publisher."""

    def __init__(self) -> None:
        factory = b.BehaviorTreeFactory()
        factory.register_behavior_tree_from_text(XML)
        bb = b.Blackboard.create()
        bb.set_int("n", 0)
        self.tree = factory.create_tree("MainTree", bb)
        self.port = free_port_pair()
        self.publisher = b.Groot2Publisher(self.tree, self.port)

    def tick(self) -> None:
        self.tree.tick_once()


class Ours:
    def __init__(self) -> None:
        self.tree = load_tree_string(XML, context=TreeContext(clock=ManualClock()),
                                     blackboard={"n": 0})
        self.monitor = TreeMonitor(self.tree, self.tree.context.clock.now)
        self.publisher = GrootPublisher(self.monitor, port=0)
        self.port = self.publisher.port

    def tick(self) -> None:
        self.tree.tick()


@pytest.fixture(scope="module")
def pair() -> Any:
    ref, ours = Reference(), Ours()
    clients = GrootClient(ref.port), GrootClient(ours.port)
    yield ref, ours, clients
    for client in clients:
        client.close()
    ours.publisher.close()
    ours.monitor.close()
    del ref.publisher


def both(clients: tuple[GrootClient, GrootClient], kind: str, *parts: Any,
         **kw: Any) -> tuple[list[bytes], list[bytes]]:
    return clients[0].request(kind, *parts, **kw), clients[1].request(kind, *parts, **kw)


def same_header(ref: list[bytes], ours: list[bytes]) -> None:
    assert len(ref[0]) == len(ours[0]) == 22
    assert ref[0][:6] == ours[0][:6]
    assert len(ref) == len(ours)


def structure(xml: str) -> tuple[list[Any], dict[str, Any]]:
    """The instances with their nodes and attributes, and the models minus description
    texts (bt-manip words its port descriptions its own way)."""
    root = parse_xml_text(xml, "fulltree.xml")
    trees: list[Any] = []
    models: dict[str, Any] = {}

    def nodes(element: Any) -> list[Any]:
        out = []
        for child in element.children:
            out.append((child.tag, dict(child.attrib), nodes(child)))
        return out

    for section in root.children:
        if section.tag == "BehaviorTree":
            trees.append((dict(section.attrib), nodes(section)))
        elif section.tag == "TreeNodesModel":
            for node in section.children:
                models[node.get("ID")] = (node.tag, sorted(
                    (p.tag, p.get("name"), p.get("type"), p.get("default"))
                    for p in node.children))
    return trees, models


def test_fulltree_has_the_same_instances_nodes_uids_and_builtin_models(pair: Any) -> None:
    _, _, clients = pair
    ref, ours = both(clients, "T")
    same_header(ref, ours)
    ref_trees, ref_models = structure(ref[1].decode())
    our_trees, our_models = structure(ours[1].decode())
    assert our_trees == ref_trees
    assert [t[0]["_fullpath"] for t in our_trees] == [
        "", "pick_one", "pick_one/Grasp::6", "Pick::9", "Pick::9/Grasp::12"]
    for node_id, model in ref_models.items():
        assert our_models.get(node_id) == model, node_id
    assert "MoveBase" not in ref_models  # robot nodes: only ours, tested in test_groot_run


def test_status_blackboard_and_transitions_agree_tick_by_tick(pair: Any) -> None:
    ref_side, our_side, clients = pair
    ref, ours = both(clients, "S")
    same_header(ref, ours)
    assert ours[1] == ref[1]
    start = both(clients, "r", "start")
    same_header(*start)
    assert int(start[1][1]) > 0
    for _ in range(TICKS):
        ref_side.tick()
        our_side.tick()
        ref, ours = both(clients, "S")
        same_header(ref, ours)
        assert ours[1] == ref[1]
        ref, ours = both(clients, "t")
        same_header(ref, ours)
        assert len(ours[1]) == len(ref[1]) > 0
        assert [ours[1][i + 6:i + 9] for i in range(0, len(ours[1]), 9)] == [
            ref[1][i + 6:i + 9] for i in range(0, len(ref[1]), 9)]
        names = "MainTree;pick_one;pick_one/Grasp::6;Pick::9;nowhere"
        ref, ours = both(clients, "B", names)
        same_header(ref, ours)
        assert msgpack.unpackb(ours[1]) == msgpack.unpackb(ref[1])
    assert msgpack.unpackb(ours[1])["pick_one"] == {"local": 7}
    stop = both(clients, "r", "stop")
    same_header(*stop)


def test_hook_requests_and_dump_agree(pair: Any) -> None:
    _, _, clients = pair
    hook = {"enabled": True, "uid": 5, "mode": 1, "once": False,
            "desired_status": "FAILURE", "position": 0}
    replies = both(clients, "I", json.dumps(hook))
    same_header(*replies)
    ref, ours = both(clients, "D")
    same_header(ref, ours)
    assert json.loads(ours[1]) == json.loads(ref[1]) == [hook]
    for kind, parts in (("X", ()), ("D", ()), ("A", ()), ("D", ())):
        ref, ours = both(clients, kind, *parts)
        same_header(ref, ours)
        assert ours[1:] == ref[1:]


@pytest.mark.parametrize("frames", [
    pytest.param(["abc"], id="short header"),
    pytest.param([b"\x02Q\x01\x00\x00\x00"], id="unknown type"),
    pytest.param([b"\x02N\x01\x00\x00\x00"], id="breakpoint reached is not a request"),
    pytest.param([b"\x02B\x01\x00\x00\x00"], id="blackboard without names"),
    pytest.param([b"\x02I\x01\x00\x00\x00"], id="hook insert without hook"),
    pytest.param([b"\x02r\x01\x00\x00\x00"], id="recording without command"),
    pytest.param([b"\x02R\x01\x00\x00\x00", b'{"uid": 999, "position": 0}'],
                 id="remove a hook of no node"),
    pytest.param([b"\x02U\x01\x00\x00\x00", json.dumps(
        {"uid": 3, "desired_status": "SUCCESS", "position": 0, "remove_when_done": True})],
        id="unlock without a hook"),
])
def test_error_replies_agree(pair: Any, frames: list[Any]) -> None:
    _, _, clients = pair
    frames = [f if isinstance(f, bytes) else f.encode() for f in frames]
    ref, ours = clients[0].raw(frames), clients[1].raw(frames)
    assert ref[0] == b"error"
    assert ours == ref


def test_other_protocol_numbers_are_answered_as_protocol_2(pair: Any) -> None:
    _, _, clients = pair
    ref, ours = both(clients, "S", protocol=9)
    same_header(ref, ours)
    assert ours[0][0] == 2


def _btcpp_btlog(path: Path) -> list[tuple[int, int]]:
    factory = b.BehaviorTreeFactory()
    factory.register_behavior_tree_from_text(XML)
    bb = b.Blackboard.create()
    bb.set_int("n", 0)
    tree = factory.create_tree("MainTree", bb)
    logger = b.FileLogger(tree, str(path))
    for _ in range(TICKS):
        tree.tick_once()
    tree.halt_tree()
    # FileLogger2 writes (and flushes) from a thread of its own, which a busy machine may not
    # run for a while, and which, destroyed before it ever ran, writes nothing: wait until the
    # file holds transitions and has not changed for half a second, all ticks being long done.
    # No logger.flush() from here: it races that thread's writes on one ofstream (seen as
    # garbage records under load).
    transitions: list[tuple[int, int]] = []
    unchanged = 0
    deadline = time.monotonic() + 60
    while unchanged < 10 and time.monotonic() < deadline:
        time.sleep(0.05)
        found = [(uid, status) for _, uid, status in read_btlog(path).transitions]
        unchanged = unchanged + 1 if found and found == transitions else 0
        transitions = found
    del logger
    return transitions


def test_btlog_has_the_transition_sequence_of_file_logger2(tmp_path: Path) -> None:
    expected = _btcpp_btlog(tmp_path / "btcpp.btlog")
    tree = load_tree_string(XML, context=TreeContext(clock=ManualClock()), blackboard={"n": 0})
    clock = tree.context.clock
    monitor = TreeMonitor(tree, clock.now)
    writer = BtlogWriter(tmp_path / "ours.btlog", monitor)
    for _ in range(TICKS):
        tree.tick()
        clock.advance(0.05)
    tree.halt()
    writer.close()
    log = read_btlog(tmp_path / "ours.btlog")
    assert [(uid, status) for _, uid, status in log.transitions] == expected
    assert len(expected) > 50
    stamps = sorted({stamp for stamp, _, _ in log.transitions})
    assert stamps == [0, 50_000, 100_000, 150_000]  # sim time of each tick and the halt (us)
    assert structure(log.xml)[0] == structure(read_btlog(tmp_path / "btcpp.btlog").xml)[0]


def test_replace_hooks_force_statuses_as_in_btcpp() -> None:
    """A replace-hook (mode 1) makes a node return its desired status without ticking it; a
    ``once`` hook goes away after its first use. Both engines, same hooks, same ticks."""
    ref, ours = Reference(), Ours()
    clients = GrootClient(ref.port), GrootClient(ours.port)
    try:
        fulltree = both(clients, "T")[1][1].decode()
        assert '<AlwaysFailure name="close" _uid="8"/>' in fulltree
        assert '_uid="15" num_cycles="2">\n' \
               '                <AlwaysSuccess name="AlwaysSuccess" _uid="16"/>' in fulltree
        hooks = [  # Grasp's AlwaysFailure 'close' succeeds; Repeat's child fails once
            {"enabled": True, "uid": 8, "mode": 1, "once": False,
             "desired_status": "SUCCESS", "position": 0},
            {"enabled": True, "uid": 16, "mode": 1, "once": True,
             "desired_status": "FAILURE", "position": 0},
        ]
        same_header(*both(clients, "I", json.dumps(hooks)))
        same_header(*both(clients, "r", "start"))
        seen: list[bytes] = []
        for _ in range(TICKS):
            ref.tick()
            ours.tick()
            ref_reply, our_reply = both(clients, "S")
            assert our_reply[1] == ref_reply[1]
            ref_reply, our_reply = both(clients, "t")
            changes = [our_reply[1][i + 6:i + 9] for i in range(0, len(our_reply[1]), 9)]
            assert changes == [
                ref_reply[1][i + 6:i + 9] for i in range(0, len(ref_reply[1]), 9)]
            seen += changes
        assert b"\x08\x00\x02" in seen and b"\x08\x00\x03" not in seen  # 'close' forced
        assert seen.count(b"\x10\x00\x03") == 1  # the once hook failed the child once
        ref_dump, our_dump = both(clients, "D")
        assert json.loads(our_dump[1]) == json.loads(ref_dump[1]) == hooks[:1]
    finally:
        for client in clients:
            client.close()
        ours.publisher.close()
        ours.monitor.close()
        del ref.publisher



def test_a_breakpoint_unlocked_with_failure_as_in_btcpp(tmp_path: Path) -> None:
    """Both publishers announce the breakpoint on PUB alike, answer STATUS alike while the
    tree waits, and a FAILURE unlock fails the node in both (BT.CPP in its own process)."""
    import subprocess
    import sys
    import threading

    from groot_client import sync_subscription

    tree_file = tmp_path / "tree.xml"
    tree_file.write_text(XML)
    port = free_port_pair()
    worker = subprocess.Popen(
        [sys.executable, str(Path(__file__).with_name("btcpp_worker.py")), str(tree_file),
         str(port)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    ours = Ours()
    clients: tuple[GrootClient, ...] = ()
    thread = threading.Thread(target=ours.tick)
    try:
        assert worker.stdin is not None and worker.stdout is not None
        read_until(worker.stdout, "ready")
        clients = GrootClient(port), GrootClient(ours.port)
        sync_subscription(clients[1], ours.publisher)
        time.sleep(1.0)  # BT.CPP's PUB socket: let the subscription connect
        hook = {"enabled": True, "uid": 5, "mode": 0, "once": False,
                "desired_status": "IDLE", "position": 0}
        same_header(*both(clients, "I", json.dumps(hook)))
        worker.stdin.write("tick\n")
        worker.stdin.flush()
        thread.start()
        notices = [wait_notice(client, clients) for client in clients]
        assert [len(n[0]) for n in notices] == [6, 6]
        assert notices[0][0][:2] == notices[1][0][:2] == b"\x02N"
        assert notices[0][1] == notices[1][1] == b"5"
        ref_status, our_status = both(clients, "S")
        assert our_status[1] == ref_status[1]
        assert status_byte(our_status[1], 4) == 1  # paused: its Sequence is RUNNING
        unlock = {"uid": 5, "desired_status": "FAILURE", "position": 0, "remove_when_done": True}
        same_header(*both(clients, "U", json.dumps(unlock)))
        read_until(worker.stdout, "ticked")
        thread.join(30)
        ref_status, our_status = both(clients, "S")
        assert our_status[1] == ref_status[1]
        assert status_byte(our_status[1], 5) == 13  # failed (forced), then reset
        ref_dump, our_dump = both(clients, "D")
        assert json.loads(our_dump[1]) == json.loads(ref_dump[1]) == []
    finally:
        for client in clients:
            client.close()
        ours.publisher.close()
        if thread.is_alive():
            thread.join(30)
        ours.monitor.close()
        if worker.stdin is not None:
            worker.stdin.close()
        try:
            worker.wait(30)
        except subprocess.TimeoutExpired:
            worker.kill()


def read_until(stream: Any, word: str) -> None:
    for line in stream:
        if line.strip() == word:
            return
    raise AssertionError(f"the BT.CPP worker ended before saying '{word}'")


def wait_notice(client: GrootClient, clients: tuple[GrootClient, ...]) -> list[bytes]:
    """The next PUB message of ``client``; meanwhile poll STATUS on every publisher, as
    Groot2 does (each request is a heartbeat that keeps the hooks enabled)."""
    import zmq

    client.sub.setsockopt(zmq.RCVTIMEO, 100)
    deadline = time.monotonic() + 60
    try:
        while time.monotonic() < deadline:
            try:
                return client.sub.recv_multipart()
            except zmq.Again:
                for other in clients:
                    other.request("S")
        raise AssertionError("no breakpoint notice")
    finally:
        client.sub.setsockopt(zmq.RCVTIMEO, client.timeout_ms)


def status_byte(reply: bytes, uid: int) -> int:
    for offset in range(0, len(reply), 3):
        if int.from_bytes(reply[offset:offset + 2], "little") == uid:
            return reply[offset + 2]
    raise KeyError(uid)
