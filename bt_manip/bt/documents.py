"""Reading BT.CPP v4 XML documents: ``<root>``, ``<include>``, trees and node models.

:func:`read_document` gathers every ``<BehaviorTree>`` and ``<TreeNodesModel>`` of a file and
of the files it includes (paths relative to the including file, recursively; cycles, a file
included twice and includes nested deeper than :data:`MAX_INCLUDE_DEPTH` are refused),
collecting every problem instead of stopping at the first one.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

from bt_manip.bt.models import NodeSpec, read_models
from bt_manip.bt.v3_convert import ConvertError, convert_v3
from bt_manip.bt.xml_parse import MAX_BYTES, Element, XmlError, parse_xml_file, parse_xml_text
from bt_manip.errors import InputError, Problem
from bt_manip.input_files import read_bounded

MAX_INCLUDE_DEPTH = 256
"""Files including files including files...: at most this many levels (like XML nesting)."""


@dataclass
class TreeDef:
    tree_id: str
    element: Element
    file: str


@dataclass
class Document:
    file: str
    trees: dict[str, TreeDef] = field(default_factory=dict)
    models: dict[str, NodeSpec] = field(default_factory=dict)
    main_tree: str | None = None
    root_line: int = 1
    problems: list[Problem] = field(default_factory=list)
    warnings: list[Problem] = field(default_factory=list)
    included: dict[str, str] = field(default_factory=dict)  # real path -> where first included
    unnamed: int = 0  # ID-less trees named so far (BehaviorTree_0, BehaviorTree_1...)


def read_document(path: str, text: str | None = None) -> Document:
    """Read ``path`` (or ``text`` named ``path``) and its includes."""
    doc = Document(path)
    _read_into(doc, path, text, stack=(), top=True)
    return doc


def read_model_file(path: str, doc: Document) -> None:
    """Add the TreeNodesModel declarations of ``path`` to ``doc``."""
    try:
        root = parse_xml_file(path)
    except XmlError as e:
        doc.problems.append(e.problem)
        return
    found = False
    candidates = [root] if root.tag == "TreeNodesModel" else root.children
    for element in candidates:
        if element.tag == "TreeNodesModel":
            found = True
            _merge_models(doc, element, path)
    if not found:
        doc.problems.append(Problem(path, root.line,
                                    "no <TreeNodesModel> found; a model file looks like "
                                    "<root BTCPP_format=\"4\"><TreeNodesModel>...</root>"))


def _merge_models(doc: Document, element: Element, file: str) -> None:
    specs, problems = read_models(element, file)
    doc.problems.extend(problems)
    for node_id, spec in specs.items():
        doc.models.setdefault(node_id, spec)


def _read_into(doc: Document, path: str, text: str | None, stack: tuple[str, ...],
               top: bool) -> None:
    try:
        root = parse_xml_text(text, path) if text is not None else parse_xml_file(path)
    except XmlError as e:
        doc.problems.append(e.problem)
        return
    if root.tag != "root":
        doc.problems.append(Problem(path, root.line,
                                    f"the top element must be <root BTCPP_format=\"4\">, "
                                    f"found <{root.tag}>"))
        return
    fmt = root.get("BTCPP_format")
    if fmt is None or fmt.strip() == "3":
        upgraded = _upgrade_v3(doc, path, text, fmt)
        if upgraded is None:
            return
        root = upgraded
    elif fmt.strip() != "4":
        doc.problems.append(Problem(path, root.line,
                                    f"BTCPP_format=\"{fmt}\" is not supported; this loader reads "
                                    "BehaviorTree.CPP version 4 files (BTCPP_format=\"4\")"))
    if top:
        doc.main_tree = root.get("main_tree_to_execute")
        doc.root_line = root.line
    here = os.path.realpath(path) if text is None else path
    single = sum(child.tag == "BehaviorTree" for child in root.children) == 1
    for child in root.children:
        if child.tag == "include":
            _include(doc, path, child, (*stack, here))
        elif child.tag == "BehaviorTree":
            _add_tree(doc, path, child, single)
        elif child.tag == "TreeNodesModel":
            _merge_models(doc, child, path)
        else:
            doc.problems.append(Problem(path, child.line,
                                        f"unexpected element <{child.tag}> under <root>; "
                                        "expected <BehaviorTree>, <include> or <TreeNodesModel>"))


def _upgrade_v3(doc: Document, path: str, text: str | None, fmt: str | None) -> Element | None:
    """The root of a BehaviorTree.CPP v3 file (``BTCPP_format`` "3" or none) converted to v4
    (:mod:`bt_manip.bt.v3_convert`), each rewrite a warning with its line; None (and the
    problem) when it cannot be read."""
    what = "has no BTCPP_format attribute" if fmt is None else 'has BTCPP_format="3"'
    try:
        raw = text if text is not None else read_bounded(path, MAX_BYTES, "file").decode("utf-8")
        v4, rewrites = convert_v3(raw)
        root = parse_xml_text(v4, path)
    except InputError as e:
        doc.problems.extend(e.problems)
        return None
    except (ConvertError, XmlError, UnicodeDecodeError) as e:
        doc.problems.append(
            e.problem if isinstance(e, XmlError)
            else Problem(path, e.line, f"malformed XML: {e.message}")
            if isinstance(e, ConvertError) else Problem(path, None, str(e)))
        return None
    doc.warnings.append(Problem(path, root.line, f"warning: <root> {what}; reading it as "
                                "BehaviorTree.CPP v3, converted to BTCPP_format=\"4\""))
    doc.warnings.extend(Problem(path, line, f"warning: v3 form: {change}")
                        for line, change in rewrites if "BTCPP_format" not in change)
    return root


def _include(doc: Document, path: str, element: Element, stack: tuple[str, ...]) -> None:
    target = element.get("path")
    if element.get("ros_pkg") is not None:
        doc.problems.append(Problem(path, element.line,
                                    "<include ros_pkg=...> needs ROS; give a path relative to "
                                    "this file instead"))
        return
    if not target:
        doc.problems.append(Problem(path, element.line,
                                    "<include> needs a path attribute, e.g. "
                                    "<include path=\"subtrees.xml\"/>"))
        return
    base = os.path.dirname(os.path.abspath(path)) if os.path.exists(path) else os.getcwd()
    resolved = os.path.normpath(os.path.join(base, target))
    if os.path.isdir(resolved):
        doc.problems.append(Problem(path, element.line,
                                    f"included path '{target}' is a directory ({resolved}); "
                                    "include an XML file, e.g. <include path=\"subtrees.xml\"/>"))
        return
    if not os.path.isfile(resolved):
        doc.problems.append(Problem(path, element.line,
                                    f"included file '{target}' not found (looked for "
                                    f"{resolved}); the path is relative to the including file"))
        return
    real = os.path.realpath(resolved)
    if real in stack:
        chain = " -> ".join(os.path.basename(p) for p in (*stack, real))
        doc.problems.append(Problem(path, element.line, f"include cycle: {chain}; remove one of "
                                                        "these includes"))
        return
    if real in doc.included:
        first = doc.included[real]
        doc.problems.append(Problem(path, element.line,
                                    f"'{target}' is already included (at {first}); include each "
                                    "file once, its trees would be defined twice"))
        return
    if len(stack) > MAX_INCLUDE_DEPTH:
        doc.problems.append(Problem(path, element.line,
                                    f"includes nested deeper than {MAX_INCLUDE_DEPTH} levels; "
                                    "bt-manip reads at most that many"))
        return
    doc.included[real] = f"{path}:{element.line}"
    _read_into(doc, resolved, None, stack, top=False)


def _add_tree(doc: Document, path: str, element: Element, single: bool) -> None:
    """Add a ``<BehaviorTree>``; the only one of its file may have no ID: BT.CPP then names
    it ``BehaviorTree_N`` (N counts such trees, from 0) and runs it as the main tree."""
    tree_id = element.get("ID")
    if not tree_id and single:
        tree_id = f"BehaviorTree_{doc.unnamed}"
        doc.unnamed += 1
    if not tree_id:
        doc.problems.append(Problem(path, element.line,
                                    "<BehaviorTree> needs an ID when a file has several, e.g. "
                                    "<BehaviorTree ID=\"Main\">"))
        return
    if tree_id in doc.trees:
        other = doc.trees[tree_id]
        doc.problems.append(Problem(path, element.line,
                                    f"BehaviorTree '{tree_id}' is defined twice (also at "
                                    f"{other.file}:{other.element.line}); rename one"))
        return
    doc.trees[tree_id] = TreeDef(tree_id, element, path)
