"""Seeded fault injection: make runs fail on purpose to prove that trees recover.

Specifications (``--inject``, repeatable):

``NAME:failure:P``  the node whose name or node ID is NAME fails with probability P each time it
                    starts (a fresh execution, not every tick of a RUNNING node), without
                    running; its reason says the failure was injected.
``slip:P``          an object held in a gripper slips out (its grasp is released) with
                    probability P per carry; robot behaviours that carry ask :meth:`slip`.
``block:P``         with probability P per navigation, an obstacle is dropped on the planned
                    route; the Navigate behaviour asks :meth:`block`.

Every draw comes from one generator seeded by the episode seed, so a run with faults is as
repeatable as one without. What was injected is kept in :attr:`FaultInjector.events` for the
run report.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bt_manip.errors import InputError, Problem

WORLD_FAULTS = ("slip", "block")


@dataclass(frozen=True)
class FaultSpec:
    """One ``--inject`` argument."""

    kind: str  # "failure" | "slip" | "block"
    probability: float
    target: str = ""  # node name or ID, for "failure"

    def text(self) -> str:
        if self.kind == "failure":
            return f"{self.target}:failure:{self.probability:g}"
        return f"{self.kind}:{self.probability:g}"


def parse_fault(text: str) -> FaultSpec:
    """Read ``NAME:failure:P``, ``slip:P`` or ``block:P``; InputError when malformed."""
    parts = text.split(":")

    def bad(why: str) -> InputError:
        return InputError(
            [
                Problem(
                    "--inject", None, f"'{text}': {why}; expected NAME:failure:P, slip:P or block:P"
                )
            ]
        )

    if len(parts) == 2 and parts[0] in WORLD_FAULTS:
        kind, target, p_text = parts[0], "", parts[1]
    elif len(parts) == 3 and parts[1] == "failure" and parts[0]:
        kind, target, p_text = "failure", parts[0], parts[2]
    elif len(parts) == 3 and parts[0]:
        raise bad(f"unknown fault kind '{parts[1]}'{_close(parts[1], ['failure'])}")
    elif len(parts) == 2 and parts[0]:
        hint = _close(parts[0], list(WORLD_FAULTS))
        if not hint:
            hint = f" (for a node, write {parts[0]}:failure:{parts[1]})"
        raise bad(f"unknown fault kind '{parts[0]}'{hint}")
    else:
        raise bad("not a fault specification")
    try:
        p = float(p_text)
    except ValueError:
        raise bad(f"probability '{p_text}' is not a number") from None
    if not 0.0 <= p <= 1.0:
        raise bad(f"probability {p} is not within 0..1")
    return FaultSpec(kind, p, target)


def _close(word: str, choices: list[str]) -> str:
    matches = difflib.get_close_matches(word, choices, n=3, cutoff=0.5)
    return " (did you mean " + ", ".join(f"'{m}'" for m in matches) + "?)" if matches else ""


def check_targets(specs: list[FaultSpec], names: set[str], ids: set[str]) -> None:
    """InputError for each node failure aimed at no node of the tree (by name or node ID)."""
    problems = []
    for spec in specs:
        if spec.kind != "failure" or spec.target in names or spec.target in ids:
            continue
        known = sorted(names | ids)
        hint = _close(spec.target, known)
        if not hint:
            shown = ", ".join(known[:12]) + (", ..." if len(known) > 12 else "")
            hint = f"; the tree's node names and IDs: {shown}"
        problems.append(Problem(
            "--inject", None,
            f"'{spec.text()}': no node of the tree is named '{spec.target}' or has that node "
            f"ID{hint}"))
    if problems:
        raise InputError(problems)


@dataclass
class FaultEvent:
    """One injected fault, for the report."""

    kind: str
    target: str
    sim_time: float


@dataclass
class FaultInjector:
    """Draws the faults of one run from a generator seeded by the run's seed."""

    specs: list[FaultSpec]
    seed: int = 0
    clock: Any = None
    events: list[FaultEvent] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._rng = np.random.default_rng([int(self.seed) & 0xFFFFFFFF, 0xFA17])

    def _now(self) -> float:
        return float(self.clock.now()) if self.clock is not None else 0.0

    def _draw(self, p: float) -> bool:
        return bool(self._rng.random() < p)

    def targets(self) -> set[str]:
        return {s.target for s in self.specs if s.kind == "failure"}

    def node_fails(self, name: str, node_id: str) -> bool:
        """Called when a node starts; True when it must fail this time."""
        for spec in self.specs:
            if (
                spec.kind == "failure"
                and spec.target in (name, node_id)
                and self._draw(spec.probability)
            ):
                self.events.append(FaultEvent("failure", spec.target, self._now()))
                return True
        return False

    def _world_fault(self, kind: str, what: str) -> bool:
        for spec in self.specs:
            if spec.kind == kind and self._draw(spec.probability):
                self.events.append(FaultEvent(kind, what, self._now()))
                return True
        return False

    def slip(self, object_name: str) -> bool:
        """Called once per carry of ``object_name``; True when it must slip out."""
        return self._world_fault("slip", object_name)

    def block(self, route: str) -> bool:
        """Called once per navigation; True when an obstacle must fall on the route."""
        return self._world_fault("block", route)

    def report(self) -> list[dict[str, Any]]:
        return [
            {"kind": e.kind, "target": e.target, "sim_time": round(e.sim_time, 3)}
            for e in self.events
        ]
