"""Runs a differential case on bt-manip, through its public API, with the oracle's schedule.

The tree is loaded with :func:`bt_manip.bt.load_tree_string` from the same XML, on a manual
clock that never moves (the generator only uses 0 ms durations), with a registry holding every
bt-manip node plus the test leaf. The result has the oracle worker's shape.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from py_trees.common import Status

from bt_manip.bt import ActionNode, NodeStatus, TreeContext, load_tree_string
from bt_manip.bt.registry import NodeRegistry, registry
from bt_manip.clock import ManualClock
from bt_manip.errors import InputError
from differential.leaf import LEAF_ID, LeafState
from differential.spec import HALT, TICK_EXACTLY_ONCE, Case


@dataclass
class TracingContext(TreeContext):
    """A tree context with the trace of the test leaves' calls."""

    trace: list[str] = field(default_factory=list)

_STATUS = {"SUCCESS": Status.SUCCESS, "FAILURE": Status.FAILURE, "RUNNING": Status.RUNNING}


def _trace(node: Any) -> list[str]:
    return node.context.trace  # type: ignore[no-any-return]


def _state(node: Any) -> LeafState:
    state = getattr(node, "_leaf_state", None)
    if state is None:
        state = node._leaf_state = LeafState(node.name)
    return state


class TestLeaf(ActionNode):
    """The test leaf (see :mod:`differential.leaf`) on bt-manip's action protocol.

    bt-manip actions are BT.CPP stateful actions: ``initialise`` runs when the leaf starts from
    IDLE (it calls onStart in ``update``), later ``update`` calls are onRunning, and
    ``terminate(INVALID)`` is a halt while RUNNING (onHalted).
    """

    NODE_ID = LEAF_ID

    def initialise(self) -> None:
        self._fresh = True

    def update(self) -> Status:
        state = _state(self)
        if self._fresh:
            self._fresh = False
            return _STATUS[state.on_start(_trace(self))]
        return _STATUS[state.on_running(_trace(self))]

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID:
            _state(self).on_halted(_trace(self))


def make_registry(overrides: dict[str, type] | None = None,
                  base: NodeRegistry | None = None) -> NodeRegistry:
    """Every node of ``base`` (default: every registered bt-manip node, and the test leaf),
    with ``overrides`` (ID -> class) in place of some."""
    reg = NodeRegistry()
    source = base or registry
    for cls in source.classes():
        reg.register(cls, builtin=source.is_builtin(cls.NODE_ID))
    if base is None:
        reg.register(TestLeaf)
    for node_id, cls in (overrides or {}).items():
        if node_id != cls.NODE_ID:
            raise ValueError(f"override for {node_id} has NODE_ID {cls.NODE_ID}")
        reg.unregister(node_id)
        reg.register(cls, builtin=True)
    return reg


def normalise(value: Any) -> list[Any]:
    """A blackboard value the way the oracle worker reports it (see ``snapshot`` there)."""
    if isinstance(value, str):
        return ["s", value]
    if isinstance(value, (bool, int, float)):
        return ["n", float(value)]
    return ["o", repr(value)]


def snapshot(bb: Any) -> dict[str, list[Any]]:
    out = {}
    for key in list(bb.keys()):
        try:
            value = bb.get(key)
        except KeyError:  # an entry without a value
            continue
        out[key] = normalise(value)
    return out


def _error_text(e: BaseException) -> str:
    return (f"{type(e).__name__}: " + (str(e).strip().splitlines() or [""])[0])[:300]


@contextmanager
def _deadline(seconds: float) -> Iterator[None]:
    """Raise TimeoutError in the code inside after ``seconds`` (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def expire(signum: int, frame: Any) -> None:
        raise TimeoutError(f"no answer within {seconds} s (a loop that never ends?)")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def run_case(case: Case, reg: NodeRegistry | None = None,
             timeout: float = 10.0) -> dict[str, Any]:
    """Load and run ``case`` on bt-manip; returns the oracle worker's result shape.

    A step that takes longer than ``timeout`` seconds is an error (TimeoutError).
    """
    with _deadline(timeout):
        return _run(case, reg)


def _run(case: Case, reg: NodeRegistry | None) -> dict[str, Any]:
    trace: list[str] = []
    context = TracingContext(clock=ManualClock(), trace=trace)
    init = {key: value for key, _, value in case.init}
    try:
        tree = load_tree_string(case.xml(), context=context, blackboard=init,
                                reg=reg or make_registry())
    except InputError as e:
        return {"load_error": _error_text(e), "steps": []}
    steps: list[dict[str, Any]] = []
    for action in case.schedule:
        step: dict[str, Any] = {"action": action, "status": None, "error": None}
        try:
            if action == HALT:
                tree.halt()
            elif action == TICK_EXACTLY_ONCE:
                step["status"] = tree.tick_exactly_once().value
            else:
                result = tree.tick()
                status = result if isinstance(result, NodeStatus) else tree.bt_status
                step["status"] = status.value
        except Exception as e:  # every failure of a tick is compared, not raised
            step["error"] = _error_text(e)
        step["events"] = trace[:]
        trace.clear()
        step["bb"] = snapshot(tree.blackboard)
        steps.append(step)
        if step["error"] is not None:
            break
    return {"load_error": None, "steps": steps}
