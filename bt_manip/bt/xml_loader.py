"""Loading BT.CPP v4 XML into a :class:`~bt_manip.bt.tree.Tree`, and validating it.

Loading happens in two passes. The check pass visits every ``<BehaviorTree>`` of the document
once and collects every problem (unknown node IDs with the closest known names, attributes that
are not ports, missing required ports, bad literals for typed ports, wrong numbers of children,
undefined or recursive SubTrees, script syntax errors); :func:`validate_file` returns them and
:func:`load_tree` raises them all in one :class:`~bt_manip.errors.InputError`. The build pass
then instantiates the main tree, each ``<SubTree>`` instance getting its own copy of its tree.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator, Mapping
from functools import cached_property
from typing import Any, cast

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.bt.attributes import (
    POST_CONDITIONS,
    PRE_CONDITIONS,
    AttributeCheck,
    closest,
    parse_condition_scripts,
)
from bt_manip.bt.blackboard import Blackboard
from bt_manip.bt.context import TreeContext
from bt_manip.bt.documents import Document, TreeDef, read_document, read_model_file
from bt_manip.bt.models import NodeSpec, PortSpec, spec_of
from bt_manip.bt.node import (
    ActionNode,
    BtNode,
    ConditionNode,
    ControlNode,
    DecoratorNode,
    TreeRuntimeError,
    children_rule,
)
from bt_manip.bt.port_rules import keys_used, one_of_problem, world_name_problem
from bt_manip.bt.ports import convert_literal, parse_reference, type_from_name
from bt_manip.bt.registry import SUBTREE_ID, NodeRegistry, registry
from bt_manip.bt.script import MAX_SCRIPT_CHARS
from bt_manip.bt.status import NodeStatus
from bt_manip.bt.subtree import SubTree
from bt_manip.bt.tree import Tree
from bt_manip.bt.xml_parse import Element
from bt_manip.errors import InputError, Problem

MAX_SUBTREE_DEPTH = 256
"""SubTrees nested in SubTrees: at most this many levels (like the nesting of XML elements)."""
MAX_NODE_DEPTH = 2048
"""Nodes nested in nodes, SubTrees expanded: at most this many levels."""
MAX_SCRIPTS_CHARS = 250_000
"""Characters of a document's scripts, each text counted once: at most this many (parsing
takes a few microseconds a character; one script alone is bounded by
:data:`~bt_manip.bt.script.MAX_SCRIPT_CHARS`)."""
MAX_TREE_NODES = 50_000
"""Nodes of one tree, SubTrees expanded: at most this many. A few SubTrees that each use the
next twice multiply (30 levels make a billion nodes); building and checking a node takes
tens of microseconds, so this bounds a tree's loading to seconds."""
FRAMES_PER_LEVEL = 8
"""Python frames that ticking, halting or walking one level of a tree may take."""

EXPLICIT_TAGS = ("Action", "Condition", "Control", "Decorator")
NAME_ATTRIBUTES = ("name", "ID")


class WorldNames:
    """What a world has by kind (``object``, ``body``, ``pose``, ``robot``: see
    :attr:`bt_manip.bt.node.BtNode.WORLD_NAMES`), for checking the names a tree's literals give;
    ``label`` names the world in messages."""

    def __init__(self, label: str, names: Mapping[str, set[str]]) -> None:
        self.label = label
        self.names = names


class _Checker:
    def __init__(self, doc: Document, reg: NodeRegistry, need_implementation: bool,
                 world: WorldNames | None = None) -> None:
        self.doc = doc
        self.reg = reg
        self.need_implementation = need_implementation
        self.world = world
        self.problems: list[Problem] = []
        self.edges: dict[str, list[tuple[str, Element, str]]] = {}
        self.shadow_hits: set[str] = set()  # shadowed IDs given a port only their model has
        self._keys: dict[str, set[str] | None] = {}

    def known_ids(self) -> set[str]:
        return set(self.reg.ids()) | set(self.doc.models) | {SUBTREE_ID}

    def spec(self, node_id: str) -> NodeSpec | None:
        cls = self.reg.get(node_id)
        if cls is not None:
            return spec_of(cls)
        return self.doc.models.get(node_id)

    def add(self, file: str, element: Element, message: str) -> None:
        self.problems.append(Problem(file, element.line, message))

    def check_all(self) -> None:
        if not self.check_script_sizes():
            return
        for tree in self.doc.trees.values():
            self.edges[tree.tree_id] = []
            roots = tree.element.children
            if len(roots) != 1:
                self.add(tree.file, tree.element,
                         f"BehaviorTree '{tree.tree_id}' must have exactly one root node, "
                         f"found {len(roots)}")
            for root in roots:
                self.check_node(root, tree)
        self.check_recursion()
        for node_id, lacking in sorted(self.shadowed.items()):
            if node_id not in self.shadow_hits:
                continue
            model, cls = self.doc.models[node_id], self.reg.get(node_id)
            assert cls is not None
            self.doc.warnings.append(Problem(
                model.file or self.doc.file, model.line,
                f"warning: the TreeNodesModel entry '{node_id}' is not used: bt-manip's own "
                f"node {node_id} ({cls.__module__}.{cls.__qualname__}) takes its place, and "
                f"it has no port {', '.join(repr(p) for p in lacking)}"))

    def shadow_note(self, node_id: str) -> str:
        """For port errors of a node whose TreeNodesModel entry a bt-manip node shadows."""
        model = self.doc.models.get(node_id)
        if model is None or node_id not in self.shadowed:
            return ""
        return (f" (the TreeNodesModel entry at {model.file}:{model.line} declares another "
                f"'{node_id}'; bt-manip's own node of that ID is used)")

    @cached_property
    def shadowed(self) -> dict[str, list[str]]:
        """IDs declared in a TreeNodesModel with ports that the bt-manip node of the same ID,
        used instead, does not have (those ports, by ID)."""
        out = {}
        for node_id, model in self.doc.models.items():
            cls = self.reg.get(node_id)
            if cls is not None and model.kind != SUBTREE_ID:
                own = spec_of(cls).ports
                lacking = [port for port in model.ports if port not in own]
                if lacking:
                    out[node_id] = lacking
        return out

    def check_script_sizes(self) -> bool:
        """Refuse a document whose scripts hold more than :data:`MAX_SCRIPTS_CHARS`
        characters, at the script that passes the limit, before any is parsed; False then."""
        seen: set[str] = set()
        total = 0
        for tree in self.doc.trees.values():
            for element in _in_order(tree.element):
                node_id = element.get("ID") if element.tag in EXPLICIT_TAGS else element.tag
                cls = self.reg.get(node_id or "")
                keys = PRE_CONDITIONS + POST_CONDITIONS + (cls.SCRIPT_PORTS if cls else ())
                for key in keys:
                    text = element.get(key)
                    if text is None or text in seen or len(text) > MAX_SCRIPT_CHARS:
                        continue  # a script too long alone is refused where it is parsed
                    seen.add(text)
                    total += len(text)
                    if total > MAX_SCRIPTS_CHARS:
                        self.add(tree.file, element,
                                 f"the scripts of this file pass {MAX_SCRIPTS_CHARS:,} "
                                 f"characters at {key} of {node_id}; bt-manip reads at most "
                                 "that many")
                        return False
        return True

    def check_node(self, element: Element, tree: TreeDef) -> None:
        file = tree.file
        if element.tag in EXPLICIT_TAGS:
            node_id = element.get("ID")
            if not node_id:
                self.add(file, element, f"<{element.tag}> needs an ID attribute naming the node, "
                                        f"e.g. <{element.tag} ID=\"MyNode\"/>")
                for child in element.children:
                    self.check_node(child, tree)
                return
        else:
            node_id = element.tag
        attributes = {k: v for k, v in element.attrib.items()
                      if k != "name" and not (k == "ID" and (element.tag in EXPLICIT_TAGS
                                                             or node_id == SUBTREE_ID))}
        if node_id == SUBTREE_ID:
            self.check_subtree(element, tree, attributes)
            return
        spec = self.spec(node_id)
        if spec is None and node_id in self.doc.trees:
            self.add(file, element,
                     f"unknown node '{node_id}': it is a <BehaviorTree> of this document; "
                     f"call it with <SubTree ID=\"{node_id}\"/>")
        elif spec is None:
            self.add(file, element,
                     f"unknown node '{node_id}'{closest(node_id, self.known_ids())}; register "
                     "it in Python or declare it in a <TreeNodesModel> (--models FILE)")
        else:
            if element.tag in EXPLICIT_TAGS and spec.kind not in (element.tag, "SubTree"):
                self.add(file, element, f"'{node_id}' is a {spec.kind}, not a {element.tag}; "
                                        f"write <{spec.kind} ID=\"{node_id}\"> or <{node_id}>")
            self.check_attributes(element, file, spec, attributes)
            self.check_children(element, file, spec)
        for child in element.children:
            self.check_node(child, tree)

    def check_attributes(self, element: Element, file: str, spec: NodeSpec,
                         attributes: dict[str, str]) -> None:
        if spec.cls is not None:
            check = spec.cls.check_attributes(attributes)
            if not check.errors:
                for message in one_of_problem(spec.cls, attributes):
                    check.errors.append((message, None))
                if self.world is not None:
                    for message in world_name_problem(spec.cls, attributes, self.world.names,
                                                      self.world.label):
                        check.errors.append((message, None))
        else:
            check = AttributeCheck()
            parse_condition_scripts(attributes, check, spec.node_id)
            for key in attributes:
                if key.startswith("_"):  # a script, or not a port (IGNORED_ATTRIBUTES)
                    continue
                if key not in spec.ports:
                    declared = ", ".join(sorted(spec.ports)) or "none"
                    check.errors.append(
                        (f"'{key}' is not a port of {spec.node_id} in its TreeNodesModel"
                         f"{closest(key, set(spec.ports))}; declared ports: {declared}", None))
                else:
                    problem = model_port_problem(spec.ports[key], attributes[key])
                    if problem is not None:
                        check.errors.append(
                            (f"bad value for port '{key}' of {spec.node_id}: {problem}", None))
            if self.need_implementation:
                check.errors.append(
                    (f"node '{spec.node_id}' is declared in a TreeNodesModel but has no "
                     "implementation; import the Python module that registers it with "
                     "--import MODULE", None))
        note = self.shadow_note(spec.node_id) if spec.cls is not None and check.errors else ""
        if note and any(key in self.shadowed[spec.node_id] for key in attributes):
            self.shadow_hits.add(spec.node_id)
        for message, column in check.errors:
            if column is not None:
                message = f"{message} (column {column} of the script)"
            if note and " is not a port of " in message:
                message += note
            self.add(file, element, message)

    def check_children(self, element: Element, file: str, spec: NodeSpec) -> None:
        n = len(element.children)
        lo, hi = spec.min_children, spec.max_children
        if n < lo or (hi is not None and n > hi):
            rule = children_rule(_Rule(lo, hi))
            self.add(file, element, f"{spec.node_id} {rule}, found {n}")
        if spec.node_id == "ReactiveSequence":  # BT.CPP's VerifyXML refuses these trees
            async_children = [c for c in element.children if c.tag == "AsyncSequence"]
            if len(async_children) > 1:
                self.add(file, element,
                         "a ReactiveSequence cannot have more than one AsyncSequence child "
                         f"(found {len(async_children)}, as BehaviorTree.CPP requires); wrap "
                         "them in one Sequence")

    def check_subtree(self, element: Element, tree: TreeDef, attributes: dict[str, str]) -> None:
        file = tree.file
        target = element.get("ID")
        if not target:
            self.add(file, element, "<SubTree> needs an ID naming a <BehaviorTree>")
        elif target not in self.doc.trees:
            defined = ", ".join(sorted(self.doc.trees)) or "none"
            self.add(file, element,
                     f"SubTree '{target}' is not defined{closest(target, set(self.doc.trees))}; "
                     f"defined trees: {defined} (add <BehaviorTree ID=\"{target}\"> or an "
                     "<include>)")
        else:
            self.edges[tree.tree_id].append((target, element, file))
            self.check_subtree_ports(element, file, target, attributes)
        attributes, missing = subtree_model_defaults(self.doc, target, attributes)
        for port in missing:
            spec = self.doc.models[target or ""]
            self.add(file, element,
                     f"SubTree '{target}' does not remap port '{port}', which its model "
                     f"({spec.file}:{spec.line}) declares without a default; add {port}=\"...\" "
                     "or a default to the model")
        for message, column in SubTree.check_attributes(attributes).errors:
            if column is not None:
                message = f"{message} (column {column} of the script)"
            self.add(file, element, message)
        if element.children:
            self.add(file, element, f"SubTree takes no children, found {len(element.children)}; "
                                    "its content is the <BehaviorTree> it names")
            for child in element.children:
                self.check_node(child, tree)

    def check_subtree_ports(self, element: Element, file: str, target: str,
                            attributes: dict[str, str]) -> None:
        """Warn of each port of a ``<SubTree>`` that its tree never reads or writes."""
        if target not in self._keys:
            defaults = {cls.NODE_ID: set(cls.DEFAULT_KEYS) for cls in self.reg.classes()
                        if cls.DEFAULT_KEYS}
            self._keys[target] = keys_used(self.doc.trees[target].element, defaults)
        used = self._keys[target]
        if used is None:
            return
        for port in attributes:
            if port.startswith("_") or port in used:
                continue
            self.doc.warnings.append(Problem(
                file, element.line,
                f"warning: SubTree '{target}' port '{port}' is never read or written by tree "
                f"'{target}'{closest(port, used)}; its value goes nowhere"))

    def check_recursion(self) -> None:
        """Report SubTree cycles, and chains of SubTrees nested deeper than the limit.

        Iterative, so that a chain of thousands of SubTrees is reported, not a RecursionError.
        """
        state: dict[str, int] = {}  # 1 = on the stack, 2 = done
        depth: dict[str, int] = {}  # SubTree levels below each tree (cycles not counted)
        nodes: dict[str, int] = {}  # nodes nested below each tree's root, SubTrees expanded
        sizes: dict[str, int] = {}  # nodes of each tree, SubTrees expanded
        below: dict[str, str | None] = {}  # the tree through which the deepest chain goes
        reported: set[tuple[str, int]] = set()
        for start in self.doc.trees:
            if start in state:
                continue
            path = [start]
            stack = [(start, 0)]
            state[start] = 1
            while stack:
                tree_id, index = stack[-1]
                edges = self.edges.get(tree_id, [])
                if index < len(edges):
                    stack[-1] = (tree_id, index + 1)
                    target, element, file = edges[index]
                    if state.get(target) == 1:
                        key = (file, element.line)
                        if key not in reported:
                            reported.add(key)
                            cycle = [*path[path.index(target):], target]
                            self.add(file, element,
                                     "recursive SubTree: " + " -> ".join(cycle)
                                     + "; a tree cannot contain itself")
                    elif target not in state:
                        state[target] = 1
                        path.append(target)
                        stack.append((target, 0))
                    continue
                stack.pop()
                path.pop()
                state[tree_id] = 2
                self._measure(tree_id, depth, nodes, below)
                sizes[tree_id] = sum(_size(root, sizes)
                                     for root in self.doc.trees[tree_id].element.children)
        self._check_depth(depth, nodes, below)
        self._check_size(sizes)

    def _measure(self, tree_id: str, depth: dict[str, int], nodes: dict[str, int],
                 below: dict[str, str | None]) -> None:
        """SubTree levels and node nesting of ``tree_id``, its SubTrees being measured."""
        best, through = 0, None
        for target, _element, _file in self.edges.get(tree_id, []):
            if target in depth and depth[target] + 1 > best:
                best, through = depth[target] + 1, target
        depth[tree_id] = best
        below[tree_id] = through
        roots = self.doc.trees[tree_id].element.children
        nodes[tree_id] = max((_nesting(root, nodes) for root in roots), default=0)

    def _check_depth(self, depth: dict[str, int], nodes: dict[str, int],
                     below: dict[str, str | None]) -> None:
        deep = [t for t in self.doc.trees if depth.get(t, 0) > MAX_SUBTREE_DEPTH]
        inner = {below[t] for t in deep}
        for tree_id in deep:
            if tree_id in inner:  # reported once, at the outermost tree of the chain
                continue
            chain = [tree_id]
            while below.get(chain[-1]) is not None and len(chain) <= depth[tree_id]:
                chain.append(cast(str, below[chain[-1]]))  # not None: the loop test
            shown = " -> ".join(chain[:3]) + " -> ... -> " + " -> ".join(chain[-2:])
            tree = self.doc.trees[tree_id]
            element = next(e for t, e, _f in self.edges[tree_id] if t == chain[1])
            self.add(tree.file, element,
                     f"SubTrees nested {depth[tree_id]} levels deep ({shown}); bt-manip "
                     f"allows at most {MAX_SUBTREE_DEPTH} levels of SubTree nesting")
        if deep:
            return
        deepest = max(self.doc.trees, key=lambda t: nodes.get(t, 0), default=None)
        if deepest is not None and nodes.get(deepest, 0) > MAX_NODE_DEPTH:
            tree = self.doc.trees[deepest]
            self.add(tree.file, tree.element,
                     f"tree '{deepest}' nests nodes {nodes[deepest]} levels deep once its "
                     f"SubTrees are expanded; bt-manip allows at most {MAX_NODE_DEPTH}")


    def _check_size(self, sizes: dict[str, int]) -> None:
        """Refuse the largest tree when it holds more than :data:`MAX_TREE_NODES` nodes."""
        largest = max(self.doc.trees, key=lambda t: sizes.get(t, 0), default=None)
        if largest is None or sizes.get(largest, 0) <= MAX_TREE_NODES:
            return
        tree = self.doc.trees[largest]
        count = sizes[largest]
        shown = f"{count:,}" if count < 10**15 else f"about {float(count):.1e}"
        self.add(tree.file, tree.element,
                 f"tree '{largest}' holds {shown} nodes once its SubTrees are expanded; "
                 f"bt-manip builds at most {MAX_TREE_NODES:,}")


def _size(root: Element, sizes: dict[str, int]) -> int:
    """Nodes under ``root`` (itself included), each SubTree counted with the nodes of its tree
    (``sizes``; a tree not in it, as in a cycle, counts none)."""
    total = 0
    stack = [root]
    while stack:
        element = stack.pop()
        total += 1
        if element.tag == SUBTREE_ID:
            total += sizes.get(element.get("ID") or "", 0)
        stack.extend(element.children)
    return total


def _in_order(root: Element) -> Iterator[Element]:
    """``root`` and the elements under it, in the order of the file."""
    stack = [root]
    while stack:
        element = stack.pop()
        yield element
        stack.extend(reversed(element.children))


def allow_depth(levels: int) -> None:
    """Raise Python's recursion limit so that a tree ``levels`` deep can be ticked and walked.

    Ticking, halting, copying and drawing a tree recurse once per level; trees are bounded
    (:data:`MAX_NODE_DEPTH`), so the limit stays bounded too.
    """
    need = min(levels, MAX_NODE_DEPTH) * FRAMES_PER_LEVEL + 1000
    if sys.getrecursionlimit() < need:
        sys.setrecursionlimit(need)


def _nesting(root: Element, nodes: dict[str, int]) -> int:
    """Depth of the node tree under ``root`` (1 for a leaf), SubTrees counted by ``nodes``."""
    best = 0
    stack = [(root, 1)]
    while stack:
        element, level = stack.pop()
        if element.tag == SUBTREE_ID:
            level += nodes.get(element.get("ID") or "", 0)
        best = max(best, level)
        stack.extend((child, level + 1) for child in element.children)
    return best


def subtree_model_defaults(doc: Document, target: str | None, attributes: dict[str, str]
                           ) -> tuple[dict[str, str], list[str]]:
    """A SubTree's attributes with the defaults of its ``<TreeNodesModel><SubTree>`` entry
    added for the ports it does not give, and the ports it should give (declared there
    without a default), as BT.CPP's ``XMLParser`` remaps them; with ``_autoremap`` the model
    is not used."""
    spec = doc.models.get(target or "")
    if spec is None or spec.kind != SUBTREE_ID:
        return attributes, []
    if attributes.get("_autoremap", "").strip().lower() in ("true", "1"):
        return attributes, []
    out = dict(attributes)
    missing = []
    for port in spec.ports.values():
        if port.name not in out:
            if port.default:
                out[port.name] = port.default
            else:
                missing.append(port.name)
    return out, missing


def model_port_problem(port: PortSpec, value: str) -> str | None:
    """What is wrong with ``value`` for a port declared in a TreeNodesModel, or None."""
    if parse_reference(value) is not None:
        return None
    if port.direction == "output":
        return (f"an output port takes a blackboard reference like \"{{{port.name}}}\", "
                f"got '{value}'")
    data_type = type_from_name(port.type_name)
    if data_type is object:
        return None
    declared = f"(its TreeNodesModel declares type=\"{port.type_name}\")"
    try:
        converted = convert_literal(value, data_type)
    except ValueError as e:
        return f"{e} {declared}"
    unsigned = port.type_name.strip().startswith(("unsigned", "uint", "size_t"))
    if unsigned and isinstance(converted, int) and converted < 0:
        return f"expected a non-negative integer, got '{value}' {declared}"
    return None


class _Rule:
    def __init__(self, lo: int, hi: int | None) -> None:
        self.MIN_CHILDREN = lo
        self.MAX_CHILDREN = hi


def _main_tree(doc: Document, tree_id: str | None) -> tuple[str | None, Problem | None]:
    wanted = tree_id or doc.main_tree
    if wanted:
        if wanted in doc.trees:
            return wanted, None
        what = "--tree-id" if tree_id else "main_tree_to_execute"
        defined = ", ".join(sorted(doc.trees)) or "none"
        return None, Problem(doc.file, doc.root_line,
                             f"{what} names tree '{wanted}', which is not defined"
                             f"{closest(wanted, set(doc.trees))}; defined trees: {defined}")
    if len(doc.trees) == 1:
        return next(iter(doc.trees)), None
    if not doc.trees:
        return None, Problem(doc.file, doc.root_line, "no <BehaviorTree> in this file")
    return None, Problem(doc.file, doc.root_line,
                         "several trees and no main_tree_to_execute; add "
                         "main_tree_to_execute=\"...\" to <root> or pass --tree-id (trees: "
                         + ", ".join(sorted(doc.trees)) + ")")


def _prepare(path: str, text: str | None, models: Iterable[str] | None, tree_id: str | None,
             reg: NodeRegistry, need_implementation: bool, world: WorldNames | None = None
             ) -> tuple[Document, str | None, list[Problem]]:
    doc = read_document(path, text)
    for model_file in models or []:
        read_model_file(model_file, doc)
    checker = _Checker(doc, reg, need_implementation, world)
    checker.check_all()
    problems = doc.problems + checker.problems
    main, problem = _main_tree(doc, tree_id)
    if problem is not None and not (doc.problems and not doc.trees):
        problems.append(problem)
    problems.sort(key=lambda p: (p.file != path, p.file, p.line or 0))
    return doc, main, problems


def validate(path: str, models: Iterable[str] | None = None, tree_id: str | None = None,
             text: str | None = None, reg: NodeRegistry | None = None,
             world: WorldNames | None = None) -> tuple[list[Problem], list[Problem]]:
    """(problems, warnings) of a tree file: everything loading checks, without running; with
    ``world``, also the names of objects, bodies, poses and robots the world lacks."""
    reg = reg or registry
    doc, main, problems = _prepare(path, text, models, tree_id, reg, False, world)
    if not problems and main is not None:
        allow_depth(_Builder.depth_of(doc, main))
        try:  # building the tree checks the types of the entries that ports share
            Tree(_Builder(doc, reg, True).tree_root(main), tree_id=main, source=path)
        except InputError as e:
            problems = list(e.problems)
    return problems, doc.warnings


def validate_file(path: str, models: Iterable[str] | None = None,
                  tree_id: str | None = None) -> list[Problem]:
    """Every problem of a tree file (nodes declared in ``models`` count as known); no raise."""
    return validate(path, models, tree_id)[0]


class _Builder:
    def __init__(self, doc: Document, reg: NodeRegistry, placeholders: bool) -> None:
        self.doc = doc
        self.reg = reg
        self.placeholders = placeholders
        self._stand_ins: dict[str, type[BtNode]] = {}

    def tree_root(self, tree_id: str) -> BtNode:
        tree = self.doc.trees[tree_id]
        return self.node(tree.element.children[0], tree.file)

    def node(self, element: Element, file: str) -> BtNode:
        node_id = element.get("ID") if element.tag in EXPLICIT_TAGS else element.tag
        assert node_id is not None
        name = element.get("name")
        attributes = {k: v for k, v in element.attrib.items() if k not in NAME_ATTRIBUTES}
        node: BtNode
        if node_id == SUBTREE_ID:
            target = element.get("ID")
            assert target is not None
            attributes = subtree_model_defaults(self.doc, target, attributes)[0]
            node = SubTree(target, self.tree_root(target), name=name, **attributes)
        else:
            cls = self.reg.get(node_id) or self._stand_in(node_id)
            children = [self.node(child, file) for child in element.children]
            try:
                if issubclass(cls, ControlNode):
                    node = cls(name, children=children, **attributes)
                elif issubclass(cls, DecoratorNode):
                    node = cls(name, child=children[0], **attributes)
                else:
                    node = cls(name, **attributes)
            except ValueError as e:  # a constructor refused its arguments
                raise InputError.single(file, element.line, str(e)) from None
        node.xml_file = file
        node.xml_line = element.line
        return node

    @staticmethod
    def depth_of(doc: Document, tree_id: str) -> int:
        """Nesting depth of the nodes of ``tree_id`` with its SubTrees expanded."""
        memo: dict[str, int] = {}
        order = [tree_id]
        stack = [tree_id]
        while stack:  # every tree reachable from tree_id (the checker refused cycles)
            for element in _in_order(doc.trees[stack.pop()].element):
                target = element.get("ID") if element.tag == SUBTREE_ID else None
                if target and target not in order:
                    order.append(target)
                    stack.append(target)
        for tid in reversed(order):  # each tree after the trees it contains
            memo[tid] = max((_nesting(r, memo) for r in doc.trees[tid].element.children),
                            default=0)
        return memo[tree_id]

    def _stand_in(self, node_id: str) -> type[BtNode]:
        if not self.placeholders:
            raise KeyError(node_id)
        if node_id not in self._stand_ins:
            self._stand_ins[node_id] = make_stand_in(self.doc.models[node_id])
        return self._stand_ins[node_id]


def make_stand_in(spec: NodeSpec) -> type[BtNode]:
    """A class standing for a node known only from a model (for ``show``); ticking it fails."""
    # abstract node classes, only subclassed here (type[BtNode] would promise instances)
    bases: dict[str, type] = {"Action": ActionNode, "Condition": ConditionNode,
                              "Control": ControlNode, "Decorator": DecoratorNode}
    base = bases.get(spec.kind, ActionNode)
    inputs = {name: PortInformation(object, required=False, description=p.description)
              for name, p in spec.ports.items() if p.direction != "output"}
    outputs = {name: PortInformation(object, required=False, description=p.description)
               for name, p in spec.ports.items() if p.direction == "output"}

    def tick_node(self: BtNode) -> NodeStatus:
        raise TreeRuntimeError(f"{self.describe()}: no implementation (declared in a model only)")

    return type(spec.node_id, (base,), {"NODE_ID": spec.node_id, "INPUT_PORTS": inputs,
                                        "OUTPUT_PORTS": outputs, "tick_node": tick_node,
                                        "update": lambda self: Status.INVALID,
                                        "__module__": __name__})


def load_tree(
    path: str,
    tree_id: str | None = None,
    models: Iterable[str] | None = None,
    context: TreeContext | None = None,
    blackboard: dict[str, Any] | Blackboard | None = None,
    *,
    text: str | None = None,
    placeholders: bool = False,
    reg: NodeRegistry | None = None,
) -> Tree:
    """Load a BT.CPP v4 XML file (or ``text``, named ``path``) into a :class:`Tree`.

    Raises :class:`~bt_manip.errors.InputError` with every problem found. With
    ``placeholders``, nodes known only from a model get stand-ins that fail when ticked (for
    showing a tree); otherwise every node needs an implementation.
    """
    reg = reg or registry
    doc, main, problems = _prepare(path, text, models, tree_id, reg, not placeholders)
    if problems:
        raise InputError(problems)
    assert main is not None
    allow_depth(_Builder.depth_of(doc, main))
    root = _Builder(doc, reg, placeholders).tree_root(main)
    tree = Tree(root, context=context, blackboard=blackboard, tree_id=main, source=path)
    tree.warnings = doc.warnings
    return tree


def load_tree_string(text: str, **kwargs: Any) -> Tree:
    """Load a tree from XML text (includes are relative to the working directory)."""
    name = kwargs.pop("path", "<string>")
    return load_tree(name, text=text, **kwargs)
