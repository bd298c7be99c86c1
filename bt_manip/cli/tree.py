"""The ``validate``, ``show`` and ``nodes`` verbs: tree files checked, printed, nodes listed.

Each verb's parser gets ``func=handler``, where ``handler(args) -> int`` returns the exit code
(0 fine, 2 bad input).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Iterable

from bt_manip.bt.display import render_dot, render_tree
from bt_manip.bt.models import write_models
from bt_manip.bt.reference import find_node, node_reference, reference_markdown, reference_text
from bt_manip.bt.registry import registry
from bt_manip.bt.xml_loader import WorldNames, load_tree, validate
from bt_manip.bundled import shipped_or_given
from bt_manip.errors import InputError, Problem
from bt_manip.outputs import check_output_file, write_text
from bt_manip.plugins import add_import_flag, import_modules
from bt_manip.sim.world_reader import parse_world

PLUGIN_PACKAGES = ("bt_manip.behaviours", "bt_manip.nav2")


def load_plugins(extra: Iterable[str] = ()) -> list[Problem]:
    """Import the modules that register non-built-in nodes; problems for those that fail."""
    problems = []
    for module in PLUGIN_PACKAGES:
        try:
            importlib.import_module(module)
        except ModuleNotFoundError as e:
            if e.name == module:
                continue
            problems.append(Problem(module, None, f"cannot import module: {e}"))
    return problems + import_modules(extra)


def _print_problems(problems: Iterable[Problem]) -> None:
    for problem in problems:
        print(str(problem), file=sys.stderr)


def _common(parser: argparse.ArgumentParser, models: bool = True) -> None:
    if models:
        parser.add_argument("--models", nargs="+", action="extend", default=[], metavar="FILE",
                            help="TreeNodesModel files declaring nodes not implemented here")
    add_import_flag(parser)


def add_validate_arguments(p: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip validate``."""
    p.description = ("Check everything loading checks and report ALL problems, each as "
                     "file:line: message.")
    p.add_argument("trees", nargs="+", type=shipped_or_given, metavar="TREE.xml")
    p.add_argument("--tree-id", default=None, help="main tree to check (default: the file's)")
    p.add_argument("--world", type=shipped_or_given, default=None, metavar="W.yaml",
                   help="also check the objects, bodies, poses and robots the tree names "
                        "against this world")
    _common(p)
    p.set_defaults(func=validate_command)


def add_show_arguments(p: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip show``."""
    p.add_argument("tree", type=shipped_or_given, metavar="TREE.xml")
    p.add_argument("--tree-id", default=None)
    p.add_argument("--dot", metavar="FILE", default=None, help="write Graphviz source to FILE")
    _common(p)
    p.set_defaults(func=show_command)


def add_nodes_arguments(p: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip nodes``."""
    p.description = ("List the registered nodes, or print one node's reference: what it does "
                     "on each status, its ports with type, unit, default and accepted values.")
    p.add_argument("name", nargs="?", default=None, metavar="NAME",
                   help="print this node's reference")
    p.add_argument("--markdown", action="store_true",
                   help="print the reference of every node as Markdown (docs/nodes.md)")
    p.add_argument("--groot", action="store_true",
                   help="print a TreeNodesModel of every registered non-built-in node (Groot2)")
    p.add_argument("--builtins", action="store_true",
                   help="with --groot, also include the BT.CPP built-ins")
    _common(p, models=False)
    p.set_defaults(func=nodes_command)


VERB_ARGUMENTS = {"validate": add_validate_arguments, "show": add_show_arguments,
                  "nodes": add_nodes_arguments}
"""The verbs of this module and the function that adds each one's arguments."""


def validate_command(args: argparse.Namespace) -> int:
    failures = load_plugins(args.imports)
    if failures:
        _print_problems(failures)
        return 2
    world = None
    if args.world:
        try:
            world = WorldNames(args.world, parse_world(args.world).names_by_kind())
        except InputError as e:
            _print_problems(e.problems)
            return 2
    status = 0
    for path in args.trees:
        problems, warnings = validate(path, args.models, args.tree_id, world=world)
        _print_problems(warnings)
        if problems:
            _print_problems(problems)
            status = 2
        else:
            print(f"{path}: OK")
    return status


def show_command(args: argparse.Namespace) -> int:
    if args.dot:
        try:
            check_output_file("--dot", args.dot)
        except InputError as e:
            _print_problems(e.problems)
            return 2
    failures = load_plugins(args.imports)
    if failures:
        _print_problems(failures)
        return 2
    try:
        tree = load_tree(args.tree, args.tree_id, args.models, placeholders=True)
    except InputError as e:
        _print_problems(e.problems)
        return 2
    _print_problems(getattr(tree, "warnings", []))
    print(render_tree(tree))
    if args.dot:
        try:
            write_text(args.dot, render_dot(tree))
        except OSError as e:
            _print_problems([Problem(args.dot, None, f"cannot write: {e.strerror}")])
            return 2
    return 0


def nodes_command(args: argparse.Namespace) -> int:
    failures = load_plugins(args.imports)
    if failures:
        _print_problems(failures)
        return 2
    if args.groot:
        classes = registry.classes(None if args.builtins else False)
        sys.stdout.write(write_models(classes))
        return 0
    if args.name is not None:
        cls, suggestions = find_node(args.name, registry)
        if cls is None:
            _print_problems([Problem("nodes", None, f"unknown node '{args.name}'{suggestions}; "
                                     "`bt-manip nodes` lists them all")])
            return 2
        sys.stdout.write(reference_text(node_reference(cls, registry)))
        return 0
    if args.markdown:
        refs = [node_reference(cls, registry) for cls in registry.classes()]
        sys.stdout.write(reference_markdown(refs))
        return 0
    for cls in registry.classes():
        tag = "built-in" if registry.is_builtin(cls.NODE_ID) else "custom"
        ports = [*cls.INPUT_PORTS, *cls.OUTPUT_PORTS]
        print(f"{cls.NODE_ID:<26} {cls.KIND:<10} {tag:<9} {', '.join(ports)}")
    return 0
