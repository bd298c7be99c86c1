"""The explicit, named rules that leave something out of the differential comparison.

Nothing else is left out. Two kinds:

- generation: a BT.CPP built-in that bt-manip does not register yet is not generated (rule
  ``missing-builtin:<ID>``, reported with the figures); ``BTM_DIFF_ALL_NODES=1`` generates
  every built-in anyway;
- comparison: a mismatch that a documented deviation explains (a BT.CPP internal-error corner
  where bt-manip keeps a saner behaviour, or a difference not matched yet) is counted under the
  rule's name instead of failing. Each such rule names the heading of
  ``docs/btcpp-differences.md`` that documents it; the test suite checks that the heading
  exists, so a rule cannot outlive its documentation.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from differential.compare import Divergence
from differential.generator import BUILTINS
from differential.spec import Case

DOC = Path(__file__).resolve().parents[3] / "docs" / "btcpp-differences.md"


def enabled_builtins() -> tuple[set[str], set[str]]:
    """(built-ins to generate, built-ins left out because bt-manip lacks them)."""
    from bt_manip.bt.registry import registry

    if os.environ.get("BTM_DIFF_ALL_NODES") == "1":
        return set(BUILTINS), set()
    missing = {node_id for node_id in BUILTINS if node_id not in registry}
    return set(BUILTINS) - missing, missing


Predicate = Callable[[Case, dict[str, Any], dict[str, Any], Divergence], bool]


@dataclass(frozen=True)
class Rule:
    """A documented deviation: a mismatch for which ``applies`` holds is not a failure."""

    name: str
    heading: str  # the heading in docs/btcpp-differences.md that documents it
    applies: Predicate


def _oracle_error(case: Case, oracle: dict[str, Any], btmanip: dict[str, Any],
                  div: Divergence, *texts: str) -> bool:
    """BT.CPP threw, at the diverging step, an error containing one of ``texts``."""
    if div.step < 0 or div.step >= len(oracle["steps"]):
        return False
    error = oracle["steps"][div.step]["error"] or ""
    return any(text in error for text in texts)


def _has(case: Case, *tags: str) -> bool:
    return any(node.tag in tags for node in case.nodes())


RULES: list[Rule] = []


def explained_by(case: Case, oracle: dict[str, Any], btmanip: dict[str, Any],
                 div: Divergence) -> Rule | None:
    """The first rule that explains this mismatch, or None."""
    for rule in RULES:
        if rule.applies(case, oracle, btmanip, div):
            return rule
    return None


def doc_headings() -> set[str]:
    """The headings (any level) of docs/btcpp-differences.md, without the ``#`` marks."""
    if not DOC.exists():
        return set()
    return {line.lstrip("#").strip() for line in DOC.read_text().splitlines()
            if line.startswith("#")}
