"""Helpers for the behaviour-tree tests: run XML trees tick by tick on a manual clock."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from bt_manip.bt import Tree, TreeContext, load_tree_string
from bt_manip.clock import ManualClock


def wrap(body: str, extra: str = "", main: str = "MainTree") -> str:
    """A BT.CPP v4 document whose main tree's root is ``body``."""
    return (f'<root BTCPP_format="4" main_tree_to_execute="{main}">'
            f'<BehaviorTree ID="MainTree">{body}</BehaviorTree>{extra}</root>')


@dataclass
class Step:
    """Before the tick: set blackboard entries, advance the clock; then expect a status."""

    expect: str
    dt: float = 0.0
    set: dict[str, Any] = field(default_factory=dict)
    bb: dict[str, Any] = field(default_factory=dict)


@dataclass
class Case:
    name: str
    xml: str
    steps: list[Step]
    extra: str = ""
    init: dict[str, Any] = field(default_factory=dict)


class Harness:
    def __init__(self, body: str, extra: str = "", init: dict[str, Any] | None = None) -> None:
        self.clock = ManualClock()
        self.tree: Tree = load_tree_string(wrap(body, extra),
                                           context=TreeContext(clock=self.clock),
                                           blackboard=dict(init or {}))

    def tick(self, dt: float = 0.0) -> str:
        if dt:
            self.clock.advance(dt)
        self.tree.tick()
        return self.tree.bt_status.value

    @property
    def bb(self) -> dict[str, Any]:
        return self.tree.blackboard.as_dict()


def run_case(case: Case) -> None:
    h = Harness(case.xml, case.extra, case.init)
    for i, step in enumerate(case.steps):
        for key, value in step.set.items():
            h.tree.blackboard.set(key, value)
        status = h.tick(step.dt)
        assert status == step.expect, f"{case.name}: tick {i + 1}: {status} != {step.expect}"
        for key, value in step.bb.items():
            assert h.bb.get(key) == value, (
                f"{case.name}: tick {i + 1}: bb[{key}] = {h.bb.get(key)!r}, expected {value!r}")
