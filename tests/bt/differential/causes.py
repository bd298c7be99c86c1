"""Naming the cause of a shrunk mismatch, so that reports group them.

Each known cause is a predicate over the shrunk case, both results and the divergence; the
first that holds names the cause. A mismatch that none explains is named by what differs and
the node IDs and attributes of its shrunk tree. These names only group reports: they never
excuse a mismatch (that is :mod:`differential.rules`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from differential.compare import Divergence
from differential.spec import HALT, Case

Detector = Callable[[Case, dict[str, Any], dict[str, Any], Divergence], bool]


def _tags(case: Case) -> set[str]:
    return {n.tag for n in case.nodes()}


def _attrs(case: Case) -> set[str]:
    return {k for n in case.nodes() for k in n.attrs}


def _step_error(result: dict[str, Any], div: Divergence) -> str:
    steps = result.get("steps", [])
    if 0 <= div.step < len(steps):
        return steps[div.step]["error"] or ""
    return ""


def _at_halt(case: Case, div: Divergence) -> bool:
    return 0 <= div.step < len(case.schedule) and case.schedule[div.step] == HALT


KNOWN: list[tuple[str, Detector]] = [
    ("BT.CPP aborted its process (an exception left a destructor)",
     lambda c, o, b, d: d.kind == "crash"),
    ("BT.CPP internal error: a skipped condition child of IfThenElse/WhileDoElse",
     lambda c, o, b, d: any(t in _step_error(o, d) for t in (
         "Something unexpected happened", "not allowed to set manually the status to IDLE"))),
    ("precondition script whose value is not a bool",
     lambda c, o, b, d: "Implicit casting to bool" in _step_error(o, d)),
    ("haltTree: halts every node and runs _onHalted even on idle nodes",
     lambda c, o, b, d: _at_halt(c, d) and "_onHalted" in _attrs(c)),
    ("script error in BT.CPP only (arithmetic on a string, assignment changing a type)",
     lambda c, o, b, d: d.kind == "error" and "Error in script" in _step_error(o, d)
     and not _step_error(b, d)),
    ("SetBlackboard into a typed entry (conversion or rejection)",
     lambda c, o, b, d: "SetBlackboard" in _tags(c) and d.kind in ("bb", "error")),
    ("UnsetBlackboard through a SubTree remapping",
     lambda c, o, b, d: {"UnsetBlackboard", "SubTree"} <= _tags(c)),
    ("Delay(0): BT.CPP returns RUNNING, then a wake-up re-ticks it",
     lambda c, o, b, d: "Delay" in _tags(c)),
    ("port type fixed when the tree is created (BT.CPP rejects the tree)",
     lambda c, o, b, d: d.kind == "load" and "created with type" in (o.get("load_error") or "")),
]


def cause_of(case: Case, oracle: dict[str, Any], btmanip: dict[str, Any],
             div: Divergence) -> str:
    """The name of the first known cause that explains the mismatch, else a signature."""
    for name, detect in KNOWN:
        if detect(case, oracle, btmanip, div):
            return name
    tags = sorted(_tags(case))
    attrs = sorted(a for a in _attrs(case) if a.startswith("_"))
    halt = " +halt" if HALT in case.schedule else ""
    return (f"{div.kind}: " + ", ".join(tags)
            + (" [" + ", ".join(attrs) + "]" if attrs else "") + halt)
