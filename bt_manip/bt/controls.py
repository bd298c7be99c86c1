"""BehaviorTree.CPP v4 control nodes, with BT.CPP's semantics.

Each docstring says what the node does on each child status, what it re-ticks next time and
which children it halts. "Reset" means: a RUNNING child is halted (its ``terminate(INVALID)``
runs once), then every child goes back to IDLE.
"""

from __future__ import annotations

import re
from typing import Any

from py_trees.ports import PortInformation

from bt_manip.bt.node import BtNode, ControlNode, TreeRuntimeError
from bt_manip.bt.registry import registry
from bt_manip.bt.script import FLOAT_EPS, to_text
from bt_manip.bt.status import NodeStatus

IDLE = NodeStatus.IDLE
RUNNING = NodeStatus.RUNNING
SUCCESS = NodeStatus.SUCCESS
FAILURE = NodeStatus.FAILURE
SKIPPED = NodeStatus.SKIPPED


class _OrderedControl(ControlNode):
    """Shared logic of Sequence, SequenceWithMemory, Fallback and their Async variants."""

    STOP_ON = FAILURE  # child status that ends the loop early
    DONE = SUCCESS  # status when every child passed
    YIELDS = False  # after a child that started and finished in this tick, yield (wake-up)

    def __init__(self, name: str | None = None, children: list[BtNode] | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, children, **attributes)
        self.current = 0
        self._skipped = 0

    def _on_stop(self) -> None:
        self.reset_children()
        self.current = 0

    def tick_node(self) -> NodeStatus:
        kids = self.bt_children()
        n = len(kids)
        if self.bt_status is IDLE:  # BT.CPP keeps the count while the node is not reset
            self._skipped = 0
        self.set_running()
        while self.current < n:
            child = kids[self.current]
            before = child.bt_status
            status = child.execute_tick()
            if status is RUNNING:
                return RUNNING
            if status is self.STOP_ON:
                self._on_stop()
                return status
            self.current += 1
            if status is SKIPPED:
                self._skipped += 1
            elif self.YIELDS and before is IDLE and self.current < n:
                self.emit_wake_up()
                return RUNNING
        all_skipped = self._skipped == n
        self.reset_children()
        self.current = 0
        self._skipped = 0
        return SKIPPED if all_skipped else self.DONE

    def halt(self) -> None:
        self.current = 0
        self._skipped = 0
        super().halt()


@registry.register(builtin=True)
class Sequence(_OrderedControl):
    """Ticks children in order.

    - child SUCCESS (or SKIPPED): go on with the next child in the same tick;
    - child RUNNING: return RUNNING; the next tick resumes from that child (earlier children
      are not ticked again);
    - child FAILURE: reset all children and return FAILURE; the next tick starts again from
      the first child.

    Returns SUCCESS when every child succeeded, SKIPPED when every child was skipped.
    """


@registry.register(builtin=True)
class SequenceWithMemory(_OrderedControl):
    """Like Sequence, but on a child's FAILURE it remembers where it was.

    - child FAILURE: halt/reset that child and the ones after it (not the ones before) and
      return FAILURE; the next tick restarts from the child that failed, not from the first;
    - child RUNNING: return RUNNING and resume from it;
    - all children SUCCESS: reset everything and return SUCCESS.

    Being halted does not rewind it either (as in BT.CPP 4).

    When a child started and finished (SUCCESS) within this tick and more children follow, it
    returns RUNNING and asks for a wake-up: ``Tree.tick()`` then ticks the tree again from the
    root at once, so reactive parents above re-check their conditions between two children.
    """

    YIELDS = True

    def _on_stop(self) -> None:
        for index in range(self.current, len(self.children)):
            self.halt_child(index)

    def halt(self) -> None:
        self._skipped = 0
        ControlNode.halt(self)


@registry.register(builtin=True)
class Fallback(_OrderedControl):
    """Ticks children in order until one does not fail.

    - child FAILURE (or SKIPPED): try the next child in the same tick;
    - child RUNNING: return RUNNING; the next tick resumes from that child;
    - child SUCCESS: reset all children and return SUCCESS.

    Returns FAILURE when every child failed, SKIPPED when every child was skipped.
    """

    STOP_ON = SUCCESS
    DONE = FAILURE


@registry.register(builtin=True)
class AsyncSequence(Sequence):
    """A Sequence that yields between children.

    As Sequence, but when a child started and succeeded within this tick and more children
    follow, it returns RUNNING and asks for a wake-up (``Tree.tick()`` ticks the root again at
    once), so reactive parents re-check their conditions between two children.
    """

    YIELDS = True


@registry.register(builtin=True)
class AsyncFallback(Fallback):
    """A Fallback that yields between children.

    As Fallback, but when a child started and failed within this tick and more children
    follow, it returns RUNNING and asks for a wake-up (``Tree.tick()`` ticks the root again at
    once).
    """

    YIELDS = True


class _ReactiveControl(ControlNode):
    STOP_ON = FAILURE
    DONE = SUCCESS

    def tick_node(self) -> NodeStatus:
        kids = self.bt_children()
        all_skipped = True
        self.set_running()
        for index, child in enumerate(kids):
            status = child.execute_tick()
            all_skipped = all_skipped and status is SKIPPED
            if status is RUNNING:
                for other in range(len(kids)):
                    if other != index:
                        self.halt_child(other)
                return RUNNING
            if status is self.STOP_ON:
                self.reset_children()
                return status
            if status is SKIPPED:
                self.halt_child(index)
        self.reset_children()
        return SKIPPED if all_skipped else self.DONE


@registry.register(builtin=True)
class ReactiveSequence(_ReactiveControl):
    """Ticks every child from the first one at each tick (conditions are re-checked).

    - child SUCCESS: go on with the next child;
    - child RUNNING: halt every other child (a child that was RUNNING further right is
      halted) and return RUNNING;
    - child FAILURE: reset all children and return FAILURE.

    Returns SUCCESS when all children succeeded in the same tick.
    """


@registry.register(builtin=True)
class ReactiveFallback(_ReactiveControl):
    """Ticks every child from the first one at each tick.

    - child FAILURE: try the next child;
    - child RUNNING: halt every other child and return RUNNING;
    - child SUCCESS: reset all children and return SUCCESS (a RUNNING child further right is
      halted).

    Returns FAILURE when all children failed in the same tick.
    """

    STOP_ON = SUCCESS
    DONE = FAILURE


def _threshold(value: int, n: int) -> int:
    return max(n + value + 1, 0) if value < 0 else value


@registry.register(builtin=True)
class Parallel(ControlNode):
    """Ticks every child that has not finished yet, at each tick.

    Succeeds as soon as ``success_count`` children succeeded, fails as soon as
    ``failure_count`` failed or success has become impossible; then it resets (halts) the
    children still RUNNING. Negative thresholds count from the number of children: -1 means
    all of them. A finished child is not ticked again until the Parallel completes.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "success_count": PortInformation(
            int, required=False, default_value=-1,
            description="number of children that must succeed; -1 means all"),
        "failure_count": PortInformation(
            int, required=False, default_value=1,
            description="number of children that must fail; -1 means all"),
    }

    def __init__(self, name: str | None = None, children: list[BtNode] | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, children, **attributes)
        self._clear()

    def _clear(self) -> None:
        self._completed: set[int] = set()
        self._successes = 0
        self._failures = 0

    def tick_node(self) -> NodeStatus:
        kids = self.bt_children()
        n = len(kids)
        success_needed = _threshold(self.get_input("success_count"), n)
        failure_needed = _threshold(self.get_input("failure_count"), n)
        if n < success_needed:
            raise TreeRuntimeError(
                f"{self.describe()}: success_count {success_needed} is more than its {n} children")
        if n < failure_needed:
            raise TreeRuntimeError(
                f"{self.describe()}: failure_count {failure_needed} is more than its {n} children")
        self.set_running()
        skipped = 0
        negative_success = self.get_input("success_count") < 0
        for index, child in enumerate(kids):
            if index not in self._completed:
                status = child.execute_tick()
                if status is SKIPPED:
                    skipped += 1
                elif status is SUCCESS:
                    self._completed.add(index)
                    self._successes += 1
                elif status is FAILURE:
                    self._completed.add(index)
                    self._failures += 1
            if self._successes >= success_needed or (
                negative_success and self._successes + skipped >= success_needed
            ):
                self._clear()
                self.reset_children()
                return SUCCESS
            if n - self._failures < success_needed or self._failures == failure_needed:
                self._clear()
                self.reset_children()
                return FAILURE
        return SKIPPED if skipped == n else RUNNING

    def halt(self) -> None:
        self._clear()
        super().halt()


@registry.register(builtin=True)
class ParallelAll(ControlNode):
    """Ticks every unfinished child at each tick until all of them finished.

    Then returns FAILURE if at least ``max_failures`` children failed (negative: counted from
    the number of children), SUCCESS otherwise, and resets the children.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "max_failures": PortInformation(
            int, required=False, default_value=1,
            description="if this many children fail, the node fails; -1 means all"),
    }

    def __init__(self, name: str | None = None, children: list[BtNode] | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, children, **attributes)
        self._completed: set[int] = set()
        self._failures = 0

    def tick_node(self) -> NodeStatus:
        kids = self.bt_children()
        n = len(kids)
        failure_threshold = _threshold(self.get_input("max_failures"), n)
        if n < failure_threshold:
            raise TreeRuntimeError(
                f"{self.describe()}: max_failures {failure_threshold} is more than its "
                f"{n} children")
        self.set_running()
        skipped = 0
        for index, child in enumerate(kids):
            if index in self._completed:
                continue
            status = child.execute_tick()
            if status is SUCCESS:
                self._completed.add(index)
            elif status is FAILURE:
                self._completed.add(index)
                self._failures += 1
            elif status is SKIPPED:
                skipped += 1
        if skipped == n:
            return SKIPPED
        if skipped + len(self._completed) >= n:
            self.reset_children()
            self._completed.clear()
            result = FAILURE if self._failures >= failure_threshold else SUCCESS
            self._failures = 0
            return result
        return RUNNING

    def halt(self) -> None:
        self._completed.clear()
        self._failures = 0
        super().halt()


@registry.register(builtin=True)
class IfThenElse(ControlNode):
    """``<IfThenElse> condition, then [, else]``.

    The first child is ticked until it finishes (it is not re-checked while a branch runs):
    SUCCESS selects the second child, FAILURE the third (or returns FAILURE when there are
    only two). The selected branch is ticked until it finishes; its status is returned and all
    children are reset.
    """

    MIN_CHILDREN = 2
    MAX_CHILDREN = 3

    def __init__(self, name: str | None = None, children: list[BtNode] | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, children, **attributes)
        self._branch = 0

    def tick_node(self) -> NodeStatus:
        kids = self.bt_children()
        self.set_running()
        if self._branch == 0:
            condition = kids[0].execute_tick()
            if condition is RUNNING:
                return RUNNING
            if condition is SUCCESS:
                self._branch = 1
            elif condition is FAILURE:
                if len(kids) == 3:
                    self._branch = 2
                else:
                    return FAILURE
            else:
                return condition
        status = kids[self._branch].execute_tick()
        if status is RUNNING:
            return RUNNING
        self.reset_children()
        self._branch = 0
        return status

    def halt(self) -> None:
        self._branch = 0
        super().halt()


@registry.register(builtin=True)
class WhileDoElse(ControlNode):
    """``<WhileDoElse> condition, do [, else]``: the condition is re-checked at every tick.

    Condition SUCCESS: halt the else branch and tick the second child; FAILURE: halt the do
    branch and tick the third child (or return FAILURE with two children). When the ticked
    branch finishes, its status is returned and all children are reset.
    """

    MIN_CHILDREN = 2
    MAX_CHILDREN = 3

    def tick_node(self) -> NodeStatus:
        kids = self.bt_children()
        self.set_running()
        condition = kids[0].execute_tick()
        if condition is RUNNING:
            return RUNNING
        status = NodeStatus.IDLE
        if condition is SUCCESS:
            if len(kids) == 3:
                self.halt_child(2)
            status = kids[1].execute_tick()
        elif condition is FAILURE:
            if len(kids) == 3:
                self.halt_child(1)
                status = kids[2].execute_tick()
            else:
                status = FAILURE
        else:
            return condition
        if status is RUNNING:
            return RUNNING
        self.reset_children()
        return status


_INT_PREFIX = re.compile(r"\s*([+-]?)(?:0[xX]([0-9a-fA-F]+)|(\d+))")
_REAL_PREFIX = re.compile(r"\s*[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf(?:inity)?|nan)",
                          re.IGNORECASE)


def _leading_int(text: str) -> int | None:
    match = _INT_PREFIX.match(text)
    if match is None:
        return None
    sign, hexa, decimal = match.groups()
    value = int(hexa, 16) if hexa else int(decimal)
    return -value if sign == "-" else value


def _switch_equal(a: str, b: str) -> bool:
    """BT.CPP's ``CheckStringEquality``: equal texts, or equal integers (decimal or 0x hex), or
    reals within float epsilon, each number read from the start of the text."""
    if a == b:
        return True
    ia, ib = _leading_int(a), _leading_int(b)
    if ia is not None and ia == ib:
        return True
    ra, rb = _REAL_PREFIX.match(a), _REAL_PREFIX.match(b)
    return bool(ra and rb and abs(float(ra.group(0)) - float(rb.group(0))) <= FLOAT_EPS)


class _Switch(ControlNode):
    """``<SwitchN variable="{v}" case_1=".." ...>``: N case children plus a default (last).

    At each tick the variable is compared with every case (as text, then as numbers); the
    child of the first match (or the default) is ticked. If another child was RUNNING, it is
    halted first. When the ticked child finishes, all children are reset. The Switch returns
    the child's status and, as in BT.CPP, does not mark itself RUNNING before ticking it (a
    Switch whose child was skipped stays IDLE).
    """

    CASES = 0

    def __init__(self, name: str | None = None, children: list[BtNode] | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, children, **attributes)
        self._running = -1

    def tick_node(self) -> NodeStatus:
        kids = self.bt_children()
        match = self.CASES
        variable = self.get_input("variable", None)
        if variable is not None:
            text = to_text(variable)
            for index in range(self.CASES):
                case = self.get_input(f"case_{index + 1}", None)
                if case is not None and _switch_equal(text, to_text(case)):
                    match = index
                    break
        if self._running != -1 and self._running != match:
            self.halt_child(self._running)
        status = kids[match].execute_tick()
        if status is SKIPPED:
            self._running = -1
        elif status is RUNNING:
            self._running = match
        else:
            self.reset_children()
            self._running = -1
        return status

    def halt(self) -> None:
        self._running = -1
        super().halt()


def _make_switch(cases: int) -> type[_Switch]:
    ports = {"variable": PortInformation(str, description="value compared with each case")}
    for i in range(1, cases + 1):
        ports[f"case_{i}"] = PortInformation(str, description=f"value selecting child {i}")
    cls = type(
        f"Switch{cases}",
        (_Switch,),
        {
            "NODE_ID": f"Switch{cases}",
            "CASES": cases,
            "MIN_CHILDREN": cases + 1,
            "MAX_CHILDREN": cases + 1,
            "INPUT_PORTS": ports,
            "__doc__": _Switch.__doc__,
            "__module__": __name__,
        },
    )
    registry.register(cls, builtin=True)
    return cls


Switch2 = _make_switch(2)
Switch3 = _make_switch(3)
Switch4 = _make_switch(4)
Switch5 = _make_switch(5)
Switch6 = _make_switch(6)
