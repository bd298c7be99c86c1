"""Shrinking a case that shows a mismatch down to a minimal one that still shows it.

Greedy reduction: candidates are tried in order, biggest cuts first, and the first candidate
that is smaller (:meth:`Case.size`) and still fails becomes the new case, until no candidate
fails any more (or the evaluation budget is spent). Candidates:

- drop a step of the schedule;
- drop a subtree definition nobody calls, inline a ``<SubTree>`` call;
- replace a node by one of its children, or by a constant leaf;
- remove a child (within the node's allowed number of children);
- drop an attribute that is optional (pre/post conditions, ports with defaults, remappings);
- shorten a script (one statement of ``a; b``, one side of ``x && y``) or a leaf's pattern;
- drop an entry of the starting blackboard.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterator

from differential.generator import DECORATORS, SEQUENCES
from differential.leaf import LEAF_ID
from differential.spec import Case, Node

OPTIONAL_PORTS = {"success_count", "failure_count", "max_failures", "then_skip", "else",
                  "if_empty"}
CONSTANT_LEAVES = ("AlwaysSuccess", "AlwaysFailure")


def min_children(tag: str) -> int:
    if tag in ("IfThenElse", "WhileDoElse"):
        return 2
    if tag in SEQUENCES or tag in ("Parallel", "ParallelAll"):
        return 1
    return -1  # fixed: decorators, switches, leaves


def _max_children(tag: str) -> int | None:
    if tag in ("IfThenElse", "WhileDoElse"):
        return 3
    if tag in DECORATORS or tag == "SubTree":
        return 1
    return None


Path = tuple[str, tuple[int, ...]]  # (tree ID, child indices from the tree's root)


def _paths(case: Case) -> list[Path]:
    out: list[Path] = []

    def visit(tree_id: str, node: Node, path: tuple[int, ...]) -> None:
        out.append((tree_id, path))
        for i, child in enumerate(node.children):
            visit(tree_id, child, (*path, i))

    visit("MainTree", case.main, ())
    for tree_id, body in case.subtrees.items():
        visit(tree_id, body, ())
    return out


def _get(case: Case, path: Path) -> Node:
    tree_id, indices = path
    node = case.main if tree_id == "MainTree" else case.subtrees[tree_id]
    for i in indices:
        node = node.children[i]
    return node


def _replace(case: Case, path: Path, new: Node) -> Case:
    out = case.copy()
    new = copy.deepcopy(new)
    tree_id, indices = path
    if not indices:
        if tree_id == "MainTree":
            out.main = new
        else:
            out.subtrees[tree_id] = new
        return out
    parent = _get(out, (tree_id, indices[:-1]))
    parent.children[indices[-1]] = new
    return out


CONDITION_SCRIPTS = ("if", "_skipIf", "_failureIf", "_successIf", "_while")


def _script_parts(code: str, condition: bool) -> list[str]:
    """Shorter scripts: one statement (for a condition, only the last, which is its value),
    or one side of ``&&``/``||``."""
    parts = []
    if ";" in code:
        statements = [p.strip() for p in code.split(";") if p.strip()]
        parts += statements[-1:] if condition else statements
    for op in ("&&", "||"):
        if op in code and ";" not in code:
            parts += [p.strip() for p in code.split(op, 1)]
    return parts


def _called(case: Case) -> set[str]:
    return {n.attrs["ID"] for n in case.nodes() if n.tag == "SubTree" and "ID" in n.attrs}


def candidates(case: Case) -> Iterator[Case]:
    """Smaller variants of ``case``, biggest cuts first."""
    for tree_id in list(case.subtrees):
        if tree_id not in _called(case):
            out = case.copy()
            del out.subtrees[tree_id]
            yield out
    for path in _paths(case):
        node = _get(case, path)
        for child in node.children:
            yield _replace(case, path, child)
        if node.tag == "SubTree" and node.attrs.get("ID") in case.subtrees:
            yield _replace(case, path, case.subtrees[node.attrs["ID"]])
        if node.children or node.tag not in CONSTANT_LEAVES:
            for tag in CONSTANT_LEAVES:
                yield _replace(case, path, Node(tag))
        lo = min_children(node.tag)
        if lo >= 0 and len(node.children) > lo:
            for i in range(len(node.children)):
                new = Node(node.tag, dict(node.attrs),
                           node.children[:i] + node.children[i + 1:])
                yield _replace(case, path, new)
    for path in _paths(case):
        node = _get(case, path)
        for key, value in node.attrs.items():
            optional = (key.startswith("_") or key in OPTIONAL_PORTS
                        or (node.tag == "SubTree" and key != "ID"))
            if optional:
                attrs = {k: v for k, v in node.attrs.items() if k != key}
                yield _replace(case, path, Node(node.tag, attrs, list(node.children)))
            if key in ("code", "if") or (key.startswith("_") and key != "_autoremap"):
                condition = key in CONDITION_SCRIPTS or node.tag == "ScriptCondition"
                for part in _script_parts(value, condition):
                    attrs = dict(node.attrs)
                    attrs[key] = part
                    yield _replace(case, path, Node(node.tag, attrs, list(node.children)))
            if node.tag == LEAF_ID and key == "name":
                head, _, pattern = value.partition("_")
                if len(pattern) > 1:
                    for cut in (pattern[:-1], pattern[1:]):
                        attrs = dict(node.attrs)
                        attrs["name"] = f"{head}_{cut}"
                        yield _replace(case, path, Node(node.tag, attrs, list(node.children)))
    for i in range(len(case.schedule)):
        out = case.copy()
        del out.schedule[i]
        if out.schedule:
            yield out
    for i in range(len(case.init)):
        out = case.copy()
        del out.init[i]
        yield out


def shrink(case: Case, still_fails: Callable[[Case], bool], budget: int = 600) -> Case:
    """The smallest variant of ``case`` found for which ``still_fails`` holds."""
    current = case
    size = current.size()
    evaluations = 0
    progress = True
    while progress and evaluations < budget:
        progress = False
        for candidate in candidates(current):
            new_size = candidate.size()
            if new_size >= size:
                continue
            evaluations += 1
            if still_fails(candidate):
                current, size, progress = candidate, new_size, True
                break
            if evaluations >= budget:
                break
    return current
