"""Comparing the two engines' results, step by step.

Per step (a ``tick`` or a ``halt``) the comparison looks at, in this order:

- ``error``: whether the step raised (BT.CPP throws; bt-manip raises). Only the fact is
  compared, not the message: the two engines word their errors differently. After a step
  that raised in both engines the run stops there (both runs stop at their first error);
- ``status``: the root status the tick returned (``tickOnce`` in BT.CPP);
- ``trace``: the test leaves' ``start``/``run``/``halt`` events during the step, in order;
- ``bb``: the root blackboard after the step.

Blackboard normalisation (the only one done): BT.CPP's Python binding cannot tell an entry's
C++ type, only convert it. Every entry is reduced to ``["s", text]`` when it holds a string
and ``["n", number]`` otherwise, where a bool is 0 or 1 and integers and doubles are compared
as numbers (equal when within 1e-12 relative). So ``1``, ``1.0`` and ``true`` compare equal,
while ``"1"`` (a string) and ``1`` do not. Entries that BT.CPP created without a value (a port
remapped to a key nothing wrote yet) are left out, as bt-manip has no such entries.

Loading is compared first: both engines must accept the tree, or both reject it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any


@dataclass
class Divergence:
    """Where and how the two runs first differ."""

    kind: str  # load, error, status, trace, bb, length, crash
    step: int  # index in the schedule (-1: loading)
    oracle: Any
    btmanip: Any

    def describe(self) -> str:
        where = "loading" if self.step < 0 else f"step {self.step + 1}"
        return f"{self.kind} differs at {where}: BT.CPP {self.oracle!r}, bt-manip {self.btmanip!r}"


def same_value(a: list[Any], b: list[Any]) -> bool:
    if a[0] != b[0]:
        return False
    if a[0] == "n":
        x, y = float(a[1]), float(b[1])
        return x == y or (math.isnan(x) and math.isnan(y)) or math.isclose(x, y, rel_tol=1e-12)
    return a[1] == b[1]


def same_bb(a: dict[str, list[Any]], b: dict[str, list[Any]]) -> bool:
    return a.keys() == b.keys() and all(same_value(a[k], b[k]) for k in a)


def bb_diff(a: dict[str, list[Any]], b: dict[str, list[Any]]) -> dict[str, Any]:
    """Only the entries that differ: key -> (BT.CPP, bt-manip); None for a missing entry."""
    out = {}
    for key in sorted(set(a) | set(b)):
        va, vb = a.get(key), b.get(key)
        if va is None or vb is None or not same_value(va, vb):
            out[key] = (_show(va), _show(vb))
    return out


def _show(value: list[Any] | None) -> Any:
    if value is None:
        return None
    if value[0] == "n":
        number = float(value[1])
        return int(number) if number.is_integer() else number
    return value[1]


def first_divergence(oracle: dict[str, Any], btmanip: dict[str, Any]) -> Divergence | None:
    """The first difference between two results, or None when they agree."""
    if oracle.get("crashed") or oracle.get("hung"):
        kind = "crash" if oracle.get("crashed") else "hang"
        return Divergence(kind, -1, kind, "ran")
    o_err, b_err = oracle.get("load_error"), btmanip.get("load_error")
    if (o_err is None) != (b_err is None):
        return Divergence("load", -1, o_err or "loaded", b_err or "loaded")
    if o_err is not None:
        return None
    o_steps, b_steps = oracle["steps"], btmanip["steps"]
    for i, (o, b) in enumerate(zip(o_steps, b_steps, strict=False)):
        if (o["error"] is None) != (b["error"] is None):
            return Divergence("error", i, o["error"] or o["status"], b["error"] or b["status"])
        if o["status"] != b["status"]:
            return Divergence("status", i, o["status"], b["status"])
        if o["events"] != b["events"]:
            return Divergence("trace", i, o["events"], b["events"])
        if not same_bb(o["bb"], b["bb"]):
            diff = bb_diff(o["bb"], b["bb"])
            return Divergence("bb", i, {k: v[0] for k, v in diff.items()},
                              {k: v[1] for k, v in diff.items()})
    if len(o_steps) != len(b_steps):
        return Divergence("length", min(len(o_steps), len(b_steps)), len(o_steps), len(b_steps))
    return None


def step_table(oracle: dict[str, Any], btmanip: dict[str, Any]) -> str:
    """Both runs side by side, one line per step, for failure messages and reports."""
    lines = []
    for name, result in (("BT.CPP", oracle), ("bt-manip", btmanip)):
        if result.get("crashed") or result.get("hung"):
            lines.append(f"{name}: worker {'crashed' if result.get('crashed') else 'hung'}")
            continue
        if result.get("load_error"):
            lines.append(f"{name}: load error: {result['load_error']}")
            continue
        lines.append(f"{name}:")
        for i, step in enumerate(result["steps"]):
            what = f"ERROR {step['error']}" if step["error"] else step["status"] or "-"
            bb = {k: _show(v) for k, v in sorted(step["bb"].items())}
            lines.append(f"  {i + 1}. {step['action']:<4} -> {what}; leaf {step['events']}; "
                         f"bb {bb}")
    return "\n".join(lines)
