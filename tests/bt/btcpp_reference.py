"""The real BehaviorTree.CPP 4.8.2 (PyPI ``behaviortreepy``) as a reference for unit tests.

``run_btcpp`` ticks a tree on BT.CPP and returns the root status after each tick; ``run_ours``
does the same on bt-manip. ``builtin_models`` reads BT.CPP's built-in node models (every node
its factory registers, with ports) from the Groot2 FULLTREE reply.
"""

from __future__ import annotations

import socket
import struct
from dataclasses import dataclass
from typing import Any

import pytest

from bt_manip.bt import Tree, TreeContext, load_tree_string
from bt_manip.bt.xml_parse import parse_xml_text
from bt_manip.clock import ManualClock


def document(body: str) -> str:
    return (f'<root BTCPP_format="4"><BehaviorTree ID="MainTree">{body}</BehaviorTree>'
            "</root>")


def btcpp() -> Any:
    return pytest.importorskip("behaviortreepy")


def run_btcpp(body: str, ticks: int, init: dict[str, Any] | None = None,
              exactly_once: bool = False) -> tuple[list[str], dict[str, str]]:
    """Root status after each tick (or 'ERROR'), and the root blackboard read as text."""
    b = btcpp()
    factory = b.BehaviorTreeFactory()
    factory.register_behavior_tree_from_text(document(body))
    bb = b.Blackboard.create()
    setters = {bool: bb.set_bool, int: bb.set_int, float: bb.set_double, str: bb.set_string}
    for key, value in (init or {}).items():
        setters[type(value)](key, value)
    tree = factory.create_tree("MainTree", bb)
    statuses = []
    for _ in range(ticks):
        try:
            status = tree.tick_exactly_once() if exactly_once else tree.tick_once()
            statuses.append(status.name)
        except Exception:  # BT.CPP reports script and port errors as exceptions
            statuses.append("ERROR")
            break
    values = {}
    for key in bb.get_keys():
        try:
            values[key] = bb.get_string(key)
        except Exception:  # an entry created by a port but never written
            continue
    tree.halt_tree()
    return statuses, values


@dataclass
class Ours:
    tree: Tree
    statuses: list[str]


def run_ours(body: str, ticks: int, init: dict[str, Any] | None = None,
             exactly_once: bool = False) -> Ours:
    tree = load_tree_string(document(body), context=TreeContext(clock=ManualClock()),
                            blackboard=dict(init or {}))
    statuses = []
    for _ in range(ticks):
        try:
            status = tree.tick_exactly_once() if exactly_once else tree.tick()
            statuses.append(status.name)
        except Exception:
            statuses.append("ERROR")
            break
    return Ours(tree, statuses)


def builtin_models() -> dict[str, dict[str, tuple[str, str | None, str | None]]]:
    """{node ID: {port: (direction, default, type)}} of BT.CPP's factory, from Groot2's
    FULLTREE."""
    b = btcpp()
    zmq = pytest.importorskip("zmq")
    factory = b.BehaviorTreeFactory()
    factory.register_behavior_tree_from_text(document("<AlwaysSuccess/>"))
    tree = factory.create_tree("MainTree", b.Blackboard.create())
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    publisher = b.Groot2Publisher(tree, port)
    context = zmq.Context()
    request = context.socket(zmq.REQ)
    request.setsockopt(zmq.RCVTIMEO, 5000)
    request.setsockopt(zmq.LINGER, 0)
    try:
        request.connect(f"tcp://127.0.0.1:{port}")
        request.send(struct.pack("<BBI", 2, ord("T"), 1))
        xml = request.recv_multipart()[1].decode()
    finally:
        request.close()
        context.term()
        del publisher
    root = parse_xml_text(xml, "fulltree.xml")
    models: dict[str, dict[str, tuple[str, str | None, str | None]]] = {}
    for section in root.children:
        if section.tag != "TreeNodesModel":
            continue
        for node in section.children:
            ports = {}
            for port in node.children:
                direction = port.tag.removesuffix("_port")
                ports[port.get("name") or ""] = (direction, port.get("default"),
                                                 port.get("type"))
            models[node.get("ID") or ""] = ports
    return models
