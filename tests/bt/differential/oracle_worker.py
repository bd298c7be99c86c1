"""Oracle worker: runs cases on the real BehaviorTree.CPP 4.8.2 (``behaviortreepy``).

Started by :mod:`differential.oracle` as ``python oracle_worker.py``. It reads one case per
line on stdin (JSON: ``xml``, ``init``, ``schedule`` of ``tick``/``tick1``/``halt``) and
writes, on the stream that was its stdout, one result line per case (JSON, see
:func:`run_case`) followed by a ``{"done": true}`` line once the tree has been destroyed.
BT.CPP's own diagnostics, which it prints on stdout, are sent to /dev/null. A tree whose
halt throws is kept alive (its destructor would abort the process); if the process dies
anyway, the parent starts a new worker.
"""

from __future__ import annotations

import json
import os
import sys
from typing import Any

import behaviortreepy as bt
from leaf import LEAF_ID, LeafState

STATUS = {"SUCCESS": bt.NodeStatus.SUCCESS, "FAILURE": bt.NodeStatus.FAILURE,
          "RUNNING": bt.NodeStatus.RUNNING}


class Leaves:
    """The test leaves of the current case: their states and the trace they append to."""

    def __init__(self) -> None:
        self.trace: list[str] = []
        self.states: dict[int, LeafState] = {}

    def state(self, node: Any) -> LeafState:
        uid = node.uid()
        if uid not in self.states:
            self.states[uid] = LeafState(node.name())
        return self.states[uid]

    def on_start(self, node: Any) -> Any:
        return STATUS[self.state(node).on_start(self.trace)]

    def on_running(self, node: Any) -> Any:
        return STATUS[self.state(node).on_running(self.trace)]

    def on_halted(self, node: Any) -> None:
        self.state(node).on_halted(self.trace)


def snapshot(bb: Any) -> dict[str, list[Any]]:
    """The root blackboard, normalised: ``["s", text]`` for strings, ``["n", float]`` else.

    Entries that exist without a value (created by a port remapping) are left out.
    """
    out: dict[str, list[Any]] = {}
    for key in bb.get_keys():
        try:
            text = bb.get_string(key)
        except Exception:  # an entry without a value yet
            continue
        try:
            bb.get_bool(key)
        except Exception as e:
            if "std::string" in str(e) or "std::__cxx11::basic_string" in str(e):
                out[key] = ["s", text]
                continue
        try:
            out[key] = ["n", bb.get_double(key)]
        except Exception:
            out[key] = ["s", text]
    return out


def _status_name(status: Any) -> str:
    return str(status).rsplit(".", 1)[-1]


def _error_text(e: BaseException) -> str:
    return (str(e).strip().splitlines() or [type(e).__name__])[0][:300]


def set_entry(bb: Any, key: str, kind: str, value: Any) -> None:
    {"int": bb.set_int, "bool": bb.set_bool, "str": bb.set_string,
     "float": bb.set_double}[kind](key, value)


def tick_once_settled(tree: Any, settle_ms: int) -> Any:
    """``tickOnce()`` in which a timer started during the tick gets ``settle_ms`` to fire.

    BT.CPP's ``tickOnce()`` re-ticks the root while it is RUNNING and a wake-up is pending,
    checking the signal without waiting. A 0 ms Delay's timer thread usually, but not always,
    signals before that check. Here the check waits up to ``settle_ms`` for the signal, which
    gives the outcome of the timer winning the race; the rest is ``Tree::tickRoot`` as is.
    """
    status = tree.tick_exactly_once()
    while status == bt.NodeStatus.RUNNING and tree.sleep(settle_ms):
        status = tree.tick_exactly_once()
    return status


def run_case(case: dict[str, Any]) -> tuple[dict[str, Any], Any]:
    """Load and run one case; returns the result and the objects to destroy afterwards."""
    leaves = Leaves()
    factory = bt.BehaviorTreeFactory()
    factory.register_simple_stateful_action(LEAF_ID, leaves.on_start, leaves.on_running,
                                            leaves.on_halted)
    bb = bt.Blackboard.create()
    for key, kind, value in case["init"]:
        set_entry(bb, key, kind, value)
    try:
        factory.register_behavior_tree_from_text(case["xml"])
        tree = factory.create_tree("MainTree", bb)
    except Exception as e:
        return {"load_error": _error_text(e), "steps": []}, (factory,)
    root_bb = tree.root_blackboard()
    settle = int(case.get("settle_ms", 0))
    steps: list[dict[str, Any]] = []
    for action in case["schedule"]:
        step: dict[str, Any] = {"action": action, "status": None, "error": None}
        try:
            if action == "tick":
                status = tree.tick_once() if settle <= 0 else tick_once_settled(tree, settle)
                step["status"] = _status_name(status)
            elif action == "tick1":
                step["status"] = _status_name(tree.tick_exactly_once())
            else:
                tree.halt_tree()
        except Exception as e:
            step["error"] = _error_text(e)
        step["events"] = leaves.trace[:]
        leaves.trace.clear()
        step["bb"] = snapshot(root_bb)
        steps.append(step)
        if step["error"] is not None:
            break
    return {"load_error": None, "steps": steps}, (tree, factory)


def main() -> None:
    results = os.fdopen(os.dup(1), "w")
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    sys.stdout = sys.stderr
    kept: list[Any] = []  # trees whose halt throws: their destructor would abort the process
    for line in sys.stdin:
        if not line.strip():
            continue
        request = json.loads(line)
        if request.get("abort"):  # lets the tests check that the parent survives an abort
            os.abort()
        result, keep = run_case(request)
        results.write(json.dumps(result) + "\n")
        results.flush()
        if len(keep) == 2:
            try:
                keep[0].halt_tree()
            except Exception:
                kept.append(keep)
        del keep  # the tree goes first, then its factory
        results.write('{"done": true}\n')
        results.flush()
    results.close()
    os._exit(0)  # no destructors for the kept trees


if __name__ == "__main__":
    main()
