"""Halting: a RUNNING node's terminate(INVALID) runs exactly once; idle nodes are not touched."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import ClassVar

import pytest
from bt_harness import wrap
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.bt import ActionNode, NodeStatus, TreeContext, load_tree_string, registry
from bt_manip.clock import ManualClock

Ports = dict[str, PortInformation]


@dataclass
class LoggingContext(TreeContext):
    """A tree context with a log of the Busy actions' lifecycles."""

    log: list[tuple[str, str]] = field(default_factory=list)


class Busy(ActionNode):
    """Test action: RUNNING until ``ticks`` ticks have passed; logs its lifecycle."""

    INPUT_PORTS: ClassVar[Ports] = {
        "ticks": PortInformation(int, required=False, default_value=1000)}

    def initialise(self) -> None:
        self.context.log.append(("init", self.name))  # type: ignore[attr-defined]
        self._count = 0

    def update(self) -> Status:
        self._count += 1
        return Status.SUCCESS if self._count >= self.get_input("ticks") else Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        self.context.log.append((new_status.name, self.name))  # type: ignore[attr-defined]


@pytest.fixture
def busy() -> Iterator[list[tuple[str, str]]]:
    registry.register(Busy)
    yield []
    registry.unregister("Busy")


def make(body: str, log: list[tuple[str, str]]):  # type: ignore[no-untyped-def]
    return load_tree_string(wrap(body), context=LoggingContext(clock=ManualClock(), log=log))


def test_tree_halt_terminates_running_leaves_once(busy: list[tuple[str, str]]) -> None:
    tree = make('<Parallel><Busy name="a"/><Busy name="b"/><Busy name="c" ticks="1"/>'
                "</Parallel>", busy)
    assert tree.tick() is NodeStatus.RUNNING
    busy.clear()
    tree.halt()
    assert sorted(busy) == [("INVALID", "a"), ("INVALID", "b")]
    tree.halt()
    assert len(busy) == 2
    assert all(n.bt_status.value == "IDLE" for n in tree.nodes())


def test_completed_leaf_terminates_once_with_its_status(busy: list[tuple[str, str]]) -> None:
    tree = make('<Sequence><Busy name="a" ticks="2"/><Busy name="b" ticks="1"/></Sequence>', busy)
    assert tree.tick() is NodeStatus.RUNNING
    assert tree.tick() is NodeStatus.SUCCESS
    assert busy == [("init", "a"), ("SUCCESS", "a"), ("init", "b"), ("SUCCESS", "b")]


def test_reactive_halt_then_restart(busy: list[tuple[str, str]]) -> None:
    tree = make('<ReactiveSequence><ScriptCondition code="ok"/><Busy name="a"/>'
                "</ReactiveSequence>", busy)
    tree.blackboard.set("ok", True)
    tree.tick()
    tree.tick()
    tree.blackboard.set("ok", False)
    assert tree.tick() is NodeStatus.FAILURE
    tree.blackboard.set("ok", True)
    tree.tick()
    assert busy == [("init", "a"), ("INVALID", "a"), ("init", "a")]


def test_timeout_halts_nested_running_nodes(busy: list[tuple[str, str]]) -> None:
    clock = ManualClock()
    tree = load_tree_string(
        wrap('<Timeout msec="100"><Sequence><Busy name="a"/></Sequence></Timeout>'),
        context=LoggingContext(clock=clock, log=busy))
    tree.tick()
    clock.advance(0.1)
    assert tree.tick() is NodeStatus.FAILURE
    assert busy == [("init", "a"), ("INVALID", "a")]
    assert tree.root.feedback_message == "timed out after 100 ms"


def test_node_records_and_feedback(busy: list[tuple[str, str]]) -> None:
    tree = make('<Sequence name="top"><Busy name="a" ticks="2"/><Busy name="a" ticks="1"/>'
                "</Sequence>", busy)
    tree.tick()
    records = tree.node_records()
    assert [(r.path, r.node_id, r.status) for r in records] == [
        ("top", "Sequence", "RUNNING"), ("top/a", "Busy", "RUNNING"), ("top/a#2", "Busy", "IDLE")]
    tree.tick()
    records = tree.node_records()
    # a root that finished is reset to IDLE by the tick, as BT.CPP's tickOnce() does
    assert [(r.status, r.last_status) for r in records] == [
        ("IDLE", "SUCCESS"), ("IDLE", "SUCCESS"), ("IDLE", "SUCCESS")]
