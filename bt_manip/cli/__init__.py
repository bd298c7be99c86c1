"""``bt-manip``: the command line. This package builds the parser and dispatches; each verb
family has its module (arguments and handler), and the work is done by the library.

Verbs:
  run TREE.xml [--world W]   tick a tree (against a world's sim clock when one is given)
  bench TREE.xml --world W   many seeded episodes in parallel, with statistics
  coverage BENCH_DIR         the branches and recoveries a bench exercised (--min for CI)
  world W.yaml               load a world, print its summary, optionally let it settle
  bim BUILDING.ifc --out D   an IFC building and its schedule to a world and schedule.json
  bim-report REPORT --png P  the floor plan of an installation run, as built
  robot init|check           write a robot descriptor from a URDF, or check one
  motion-bench DIR --urdf U  plan MotionBenchMaker arm problems, figures per family
  validate TREE.xml          check a tree without running it, listing every problem
  convert V3.xml [-o OUT]    a BehaviorTree.CPP v3 tree in its v4 form
  show TREE.xml              print a tree as text (or Graphviz with --dot)
  nodes [--groot]            list registered nodes (TreeNodesModel XML with --groot)
  demo [--out DIR]           Scenario A headless: summary, run report, replay page
  examples [copy DIR]        list the shipped trees, worlds and robots, or copy them
  schema [NAME]              list the JSON Schemas of the output files, or print one

A tree or world named by a relative path that does not exist here but is a shipped example
(``trees/husky_carry_wall.xml``) is read from the shipped examples (see bt_manip.bundled).

Exit codes: 0 success, 1 the tree failed or ran out of budget, 2 bad input, 130 interrupted.

The verb modules are imported only for the verb that runs (``--help`` and ``--version`` need
none): each one's ``VERB_ARGUMENTS`` maps its verbs to the function that adds their arguments.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import Any

from bt_manip import __version__
from bt_manip.errors import InputError, Problem
from bt_manip.run.interrupts import terminate_as_interrupt
from bt_manip.run.status import EXIT_BAD_INPUT, EXIT_INTERRUPTED

__all__ = ["bb_value", "build_parser", "main"]


@dataclass(frozen=True)
class Verb:
    """A verb of the command line: its name, the module of ``bt_manip.cli`` that holds it, and
    its line in ``bt-manip --help``."""

    name: str
    module: str
    help: str


VERBS = (
    Verb("run", "run", "tick a tree until it succeeds, fails or runs out of budget"),
    Verb("bench", "bench", "run many seeded episodes and report statistics"),
    Verb("coverage", "coverage",
         "which branches and recoveries of the tree a bench exercised"),
    Verb("world", "world", "load a world and print its summary"),
    Verb("bim", "bim",
         "an IFC building model and its schedule to a world and the elements to install"),
    Verb("bim-report", "bim",
         "the floor plan of an installation run, elements coloured by their deviation"),
    Verb("robot", "robot", "write a robot descriptor from a URDF, or check one"),
    Verb("motion-bench", "motion_bench",
         "plan MotionBenchMaker arm problems and report solved counts, times and lengths"),
    Verb("demo", "run", "run Scenario A headless; write its report and replay page"),
    Verb("examples", "examples", "list the shipped trees, worlds and robots, or copy them"),
    Verb("schema", "schema", "list the JSON Schemas of bt-manip's output files, or print one"),
    Verb("validate", "tree", "check tree files without running them"),
    Verb("convert", "convert", "write a BehaviorTree.CPP v3 tree file in its v4 form"),
    Verb("show", "tree", "print a tree as text (and Graphviz with --dot)"),
    Verb("nodes", "tree", "list registered nodes, or export a TreeNodesModel"),
)
"""The verbs, in the order ``bt-manip --help`` lists them."""


class Parser(argparse.ArgumentParser):
    """argparse that reports bad arguments with exit code 2 and one line, no usage dump."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: {message} (see {self.prog} --help)\n")


def build_parser(verbs: Collection[str] | None = None) -> argparse.ArgumentParser:
    """The parser of ``bt-manip``. Every verb is listed; only those of ``verbs`` (all when
    None) get their arguments, which imports their modules."""
    parser = Parser(
        prog="bt-manip",
        description="Behaviour-tree tasks for mobile manipulators "
        "in PyBullet (BehaviorTree.CPP v4 XML).",
    )
    parser.add_argument("--version", action="version", version=f"bt-manip {__version__}")
    sub = parser.add_subparsers(dest="verb", metavar="VERB", parser_class=Parser)
    sub.required = True
    for verb in VERBS:
        verb_parser = sub.add_parser(verb.name, help=verb.help)
        if verbs is None or verb.name in verbs:
            module = importlib.import_module(f"{__name__}.{verb.module}")
            module.VERB_ARGUMENTS[verb.name](verb_parser)
    return parser


def _verb_of(argv: Sequence[str]) -> list[str]:
    """The verb ``argv`` names (its first word that is not an option: ``bt-manip`` itself takes
    no option with a value), as a list of none or one."""
    names = {verb.name for verb in VERBS}
    for word in argv:
        if not word.startswith("-"):
            return [word] if word in names else []
    return []


def _print_problems(problems: Sequence[Problem]) -> None:
    for problem in problems:
        print(problem, file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``bt-manip`` console script; returns the exit code."""
    words = sys.argv[1:] if argv is None else list(argv)
    args = build_parser(_verb_of(words)).parse_args(words)
    try:
        with terminate_as_interrupt():
            return int(args.func(args))
    except InputError as exc:
        _print_problems(exc.problems)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        return 0


def __getattr__(name: str) -> Any:
    """``bb_value``, at its old place (it is :func:`bt_manip.bt.blackboard.bb_value`)."""
    if name == "bb_value":
        from bt_manip.bt.blackboard import bb_value

        return bb_value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
