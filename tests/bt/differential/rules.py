"""The explicit, named rules that leave something out of the differential comparison.

Nothing else is left out. Two kinds:

- generation: a BT.CPP built-in that bt-manip does not register yet is not generated (rule
  ``missing-builtin:<ID>``, reported with the figures); ``BTM_DIFF_ALL_NODES=1`` generates
  every built-in anyway;
- comparison: a mismatch that a documented deviation explains (a BT.CPP internal-error corner
  where bt-manip keeps a saner behaviour, or a difference not matched yet) is counted under the
  rule's name instead of failing. Each such rule names the heading of
  ``docs/btcpp-differences.md`` and the entry under it that document it; the test suite checks
  that both exist, so a rule cannot outlive its documentation. Where it can, a rule proves its
  claim: bt-manip is run again with BT.CPP's behaviour for the node concerned (a test-only
  subclass doing what BT.CPP's source does), and the rule applies only if the two runs then
  agree completely.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bt_manip.bt.registry import NodeRegistry
from differential.compare import Divergence
from differential.generator import BUILTINS
from differential.spec import Case

DOC = Path(__file__).resolve().parents[3] / "docs" / "btcpp-differences.md"


@dataclass(frozen=True)
class NotGenerated:
    """A documented reason to leave a built-in out of the random trees."""

    name: str
    node_id: str
    heading: str  # the heading in docs/btcpp-differences.md that documents it
    row: str  # text of the section under that heading that documents it


NOT_GENERATED = [
    # BT.CPP's Delay starts a timer thread even for 0 ms; whether it fires before the Delay
    # looks (same pass) or before tickOnce looks at the wake-up (second pass), or neither,
    # differs from run to run (BT.CPP gives 2-3 outcomes on one tree). bt-manip always takes
    # the second pass. ``BTM_DIFF_DELAY=1`` generates Delay anyway (see campaign.TIMERS).
    NotGenerated("delay-zero-timer-race", "Delay", "Time", "comparisons of Delay(0) can"),
]


def enabled_builtins() -> tuple[set[str], set[str]]:
    """(built-ins to generate, the others as ``node ID (rule)``).

    Left out: the documented ``NOT_GENERATED`` ones, and (rule ``missing-builtin``) those that
    bt-manip does not register. ``BTM_DIFF_ALL_NODES=1`` generates every built-in.
    """
    from bt_manip.bt.registry import registry

    if os.environ.get("BTM_DIFF_ALL_NODES") == "1":
        return set(BUILTINS), set()
    left_out = {node_id: "missing-builtin" for node_id in BUILTINS if node_id not in registry}
    if os.environ.get("BTM_DIFF_DELAY") != "1":
        left_out.update({rule.node_id: rule.name for rule in NOT_GENERATED})
    return set(BUILTINS) - set(left_out), {f"{k} ({v})" for k, v in left_out.items()}


# (case, BT.CPP's result, bt-manip's result, the divergence, the registry bt-manip ran with)
Predicate = Callable[[Case, dict[str, Any], dict[str, Any], Divergence, NodeRegistry], bool]


@dataclass(frozen=True)
class Rule:
    """A documented deviation: a mismatch for which ``applies`` holds is not a failure."""

    name: str
    heading: str  # the heading in docs/btcpp-differences.md that documents it
    row: str  # text of the entry under that heading that documents it
    applies: Predicate


def _oracle_error(oracle: dict[str, Any], div: Divergence, text: str) -> bool:
    """BT.CPP threw, at the diverging step, an error containing ``text``."""
    if div.step < 0 or div.step >= len(oracle["steps"]):
        return False
    return text in (oracle["steps"][div.step]["error"] or "")


def _has(case: Case, *tags: str) -> bool:
    return any(node.tag in tags for node in case.nodes())


def _agrees_with(overrides: dict[str, type], case: Case, oracle: dict[str, Any],
                 div: Divergence, reg: NodeRegistry) -> bool:
    """Whether bt-manip (``reg``), with BT.CPP's behaviour for the ``overrides`` node IDs,
    loads the tree and agrees with BT.CPP at every step, or up to a later step whose
    difference another active rule explains (two documented deviations in one run)."""
    from differential.btmanip_runner import make_registry, run_case
    from differential.compare import first_divergence

    again_reg = make_registry(overrides, base=reg)
    again = run_case(case, again_reg)
    if again["load_error"] is not None:
        return False
    later = first_divergence(oracle, again)
    if later is None:
        return True
    if later.step <= div.step:
        return False
    return any(rule.applies(case, oracle, again, later, again_reg) for rule in active_rules())


def _btcpp_precondition() -> type:
    from bt_manip.bt.decorators import Precondition

    class BtcppPrecondition(Precondition):
        """BT.CPP 4.8.2's Precondition: no ``halt()`` of its own, so the flag saying that the
        child runs survives a halt and the next start ticks the child without checking ``if``."""

        NODE_ID = "Precondition"

        def halt(self) -> None:
            running = self._child_running
            super().halt()
            self._child_running = running

    return BtcppPrecondition


def _btcpp_entry_updated(node_id: str) -> type:
    from bt_manip.bt import entry_updates

    base = getattr(entry_updates, node_id)

    class BtcppEntryUpdated(base):  # type: ignore[misc, valid-type]
        """BT.CPP 4.8.2's ``EntryUpdatedDecorator::halt()``: forgets that the child runs but
        does not halt it."""

        def halt(self) -> None:
            self._child_running = False
            self.reset_status()

    BtcppEntryUpdated.NODE_ID = node_id
    return BtcppEntryUpdated


def _precondition_halt(case: Case, oracle: dict[str, Any], btmanip: dict[str, Any],
                       div: Divergence, reg: NodeRegistry) -> bool:
    return _has(case, "Precondition") and _agrees_with(
        {"Precondition": _btcpp_precondition()}, case, oracle, div, reg)


def _entry_updated_halt(case: Case, oracle: dict[str, Any], btmanip: dict[str, Any],
                        div: Divergence, reg: NodeRegistry) -> bool:
    ids = [i for i in ("SkipUnlessUpdated", "WaitValueUpdate") if _has(case, i)]
    return bool(ids) and _agrees_with({i: _btcpp_entry_updated(i) for i in ids}, case, oracle,
                                      div, reg)


def _written_keys(case: Case, bb: dict[str, list[Any]], copies: bool | None = None) -> set[str]:
    """Keys the SetBlackboard nodes write (``copies``: only those with ``value="{src}"``,
    False: only those with a text value, None: all). ``output_key="{k}"`` writes the entry
    named by the value of k, read in bt-manip's blackboard ``bb``."""
    keys = set()
    for node in case.nodes():
        if node.tag != "SetBlackboard":
            continue
        if copies is not None and node.attrs.get("value", "").startswith("{") != copies:
            continue
        key = node.attrs.get("output_key", "")
        if key.startswith("{") and key.endswith("}"):
            named = bb.get(key[1:-1])
            if named is None or named[0] != "s":
                continue
            key = named[1]
        keys.add(key)
    return keys


def _set_blackboard_text(case: Case, oracle: dict[str, Any], btmanip: dict[str, Any],
                         div: Divergence, reg: NodeRegistry) -> bool:
    """BT.CPP lacks (holds no value in) an entry that bt-manip holds as text and that a
    SetBlackboard writes: BT.CPP 4.8.2 nests a ``BT::Any`` in a text entry."""
    if div.step < 0:
        return False
    o_bb, b_bb = oracle["steps"][div.step]["bb"], btmanip["steps"][div.step]["bb"]
    written = _written_keys(case, b_bb)
    if any(key not in o_bb and value[0] == "s" for key, value in b_bb.items()
           if key in written):
        return True
    # BT.CPP's entry, reading as "not initialized", takes what a script assigns next; bt-manip
    # refuses a number into the entry, which holds text.
    error = btmanip["steps"][div.step]["error"] or ""
    return (div.kind == "error" and oracle["steps"][div.step]["error"] is None
            and "holds a string" in error
            and any(f"entry [{key}]" in error for key in written))


INTERNAL = "Where BT.CPP throws an internal error or breaks its own contract"

RULES: list[Rule] = [
    Rule("if-then-else-skipped-condition", INTERNAL, "IfThenElse whose condition is SKIPPED",
         lambda c, o, b, d, r: _oracle_error(o, d, "Something unexpected happened in IfThenElse")),
    Rule("while-do-else-skipped-condition", INTERNAL, "WhileDoElse whose condition is SKIPPED",
         lambda c, o, b, d, r: _has(c, "WhileDoElse") and _oracle_error(
             o, d, "you are not allowed to set manually the status to IDLE")),
    Rule("precondition-flag-survives-halt", INTERNAL, "Precondition halted while its child runs",
         _precondition_halt),
    Rule("entry-updated-decorator-keeps-child-running", INTERNAL,
         "SkipUnlessUpdated / WaitValueUpdate halted while their child runs", _entry_updated_halt),
    Rule("set-blackboard-text-into-text-entry", INTERNAL,
         "SetBlackboard writing text into an entry that holds text", _set_blackboard_text),
    Rule("text-into-entry-port-entry", INTERNAL,
         "Text written (by SetBlackboard or a script) into an entry created by the `entry` port",
         lambda c, o, b, d, r: _has(c, "WasEntryUpdated", "SkipUnlessUpdated", "WaitValueUpdate")
         and _oracle_error(o, d, "convertFromString for this type: BT::Any")),
    Rule("btcpp-aborts", INTERNAL, "BT.CPP aborts the process",
         lambda c, o, b, d, r: d.kind == "crash" and b.get("load_error") is not None),
]


def _copy_across_types(case: Case, oracle: dict[str, Any], btmanip: dict[str, Any],
                       div: Divergence, reg: NodeRegistry) -> bool:
    copies = any(n.tag == "SetBlackboard" and n.attrs.get("value", "").startswith("{")
                 for n in case.nodes())
    return copies and _oracle_error(oracle, div, "once declared, the type of a port shall "
                                    "not change") and _oracle_error(oracle, div, "[BT::Any]")


def _into_script_entry(case: Case, oracle: dict[str, Any], btmanip: dict[str, Any],
                       div: Divergence, reg: NodeRegistry) -> bool:
    """BT.CPP holds no value in an entry that bt-manip holds (as a number for text written;
    as anything for a copied value) and that a SetBlackboard writes."""
    if div.step < 0:
        return False
    o_bb, b_bb = oracle["steps"][div.step]["bb"], btmanip["steps"][div.step]["bb"]
    texts, copies = _written_keys(case, b_bb, False), _written_keys(case, b_bb, True)
    return any(key not in o_bb and ((key in texts and value[0] == "n") or key in copies)
               for key, value in b_bb.items())


def _refused_by_btcpp(text: str) -> Predicate:
    def applies(case: Case, oracle: dict[str, Any], btmanip: dict[str, Any],
                div: Divergence, reg: NodeRegistry) -> bool:
        return (div.kind == "load" and btmanip.get("load_error") is None
                and text in (oracle.get("load_error") or ""))

    return applies


NOT_YET = "Not yet matched"

# Differences that bt-manip means to match but does not yet. Each is active only while the
# doc lists it under "Not yet matched" (see active_rules), so matching it and removing the
# entry makes its mismatches fail the test again if the match is incomplete.
PENDING: list[Rule] = [
    Rule("set-blackboard-copy-across-types", NOT_YET,
         "SetBlackboard copying an entry into an entry of another type", _copy_across_types),
    Rule("set-blackboard-into-script-entry", NOT_YET,
         "SetBlackboard writing text into a number entry created by a script",
         _into_script_entry),
    Rule("set-blackboard-retypes-to-any", NOT_YET,
         "retypes any entry that is not strongly typed",
         lambda c, o, b, d, r: _has(c, "SetBlackboard") and d.kind == "error"
         and _oracle_error(o, d, "to type [BT::Any]")),
    Rule("reactive-sequence-two-async-sequences", NOT_YET,
         "ReactiveSequence with two AsyncSequence children",
         _refused_by_btcpp("cannot have more than one async child")),
    Rule("port-type-against-initial-entry", NOT_YET,
         "A port bound to an entry of another type given before the tree is built",
         _refused_by_btcpp("was initially created with type")),
]


def documented(rule: Rule | NotGenerated, sections: dict[str, str] | None = None) -> bool:
    """Whether the doc has the rule's heading and, under it, its row text (lines may wrap)."""
    sections = doc_sections() if sections is None else sections
    text = sections.get(rule.heading)
    return text is not None and " ".join(rule.row.split()) in " ".join(text.split())


def active_rules() -> list[Rule]:
    """RULES, and the PENDING rules that the doc lists under "Not yet matched"."""
    sections = doc_sections()
    return [*RULES, *(r for r in PENDING if documented(r, sections))]


def doc_sections() -> dict[str, str]:
    """Heading (any level, without the ``#`` marks) -> text of its section, from
    docs/btcpp-differences.md."""
    sections: dict[str, str] = {}
    heading = ""
    for line in DOC.read_text().splitlines() if DOC.exists() else []:
        if line.startswith("#"):
            heading = line.lstrip("#").strip()
            sections[heading] = ""
        elif heading:
            sections[heading] += line + "\n"
    return sections
