"""The stateful test leaf ``TestLeaf``, registered identically in both engines.

Nodes registered from Python in BT.CPP cannot declare ports, so the leaf's behaviour is encoded
in its name: ``T<n>_<pattern>``, where each letter of the pattern is a status (``S`` SUCCESS,
``F`` FAILURE, ``R`` RUNNING). ``onStart`` returns the first letter; the k-th ``onRunning``
since that start returns letter k (the last letter once the pattern is used up). Every
callback appends ``<name>:start``, ``<name>:run`` or ``<name>:halt`` to the run's trace.

This module is imported by the oracle worker too: it must not import bt-manip.
"""

from __future__ import annotations

from dataclasses import dataclass

LEAF_ID = "TestLeaf"
LETTERS = {"S": "SUCCESS", "F": "FAILURE", "R": "RUNNING"}


def leaf_name(index: int, pattern: str) -> str:
    return f"T{index}_{pattern}"


def pattern_of(name: str) -> str:
    """The status pattern in a leaf's name; a name without one behaves as ``S``."""
    _, _, pattern = name.partition("_")
    pattern = "".join(ch for ch in pattern if ch in LETTERS)
    return pattern or "S"


@dataclass
class LeafState:
    """Per-instance state: how many ``onRunning`` calls since the last ``onStart``."""

    name: str
    runs: int = 0

    def on_start(self, trace: list[str]) -> str:
        trace.append(f"{self.name}:start")
        self.runs = 0
        return LETTERS[pattern_of(self.name)[0]]

    def on_running(self, trace: list[str]) -> str:
        trace.append(f"{self.name}:run")
        self.runs += 1
        pattern = pattern_of(self.name)
        return LETTERS[pattern[min(self.runs, len(pattern) - 1)]]

    def on_halted(self, trace: list[str]) -> None:
        trace.append(f"{self.name}:halt")
