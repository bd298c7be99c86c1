"""``bt-manip``: the command line. Argument parsing only; the work is done by the modules.

Verbs:
  run TREE.xml [--world W]   tick a tree (against a world's sim clock when one is given)
  bench TREE.xml --world W   many seeded episodes in parallel, with statistics
  world W.yaml               load a world, print its summary, optionally let it settle
  bim BUILDING.ifc --out D   an IFC building and its schedule to a world and schedule.json
  bim-report REPORT --png P  the floor plan of an installation run, as built
  validate TREE.xml          check a tree without running it, listing every problem
  show TREE.xml              print a tree as text (or Graphviz with --dot)
  nodes [--groot]            list registered nodes (TreeNodesModel XML with --groot)
  demo [--out DIR]           Scenario A headless: summary, run report, replay page
  examples [copy DIR]        list the shipped trees, worlds and robots, or copy them
  schema [NAME]              list the JSON Schemas of the output files, or print one

A tree or world named by a relative path that does not exist here but is a shipped example
(``trees/husky_carry_wall.xml``) is read from the shipped examples (see bt_manip.bundled).

Exit codes: 0 success, 1 the tree failed or ran out of budget, 2 bad input, 130 interrupted.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from bt_manip.bundled import shipped_or_given
from bt_manip.errors import InputError, Problem
from bt_manip.plugins import add_import_flag
from bt_manip.run.interrupts import terminate_as_interrupt
from bt_manip.runner import EXIT_BAD_INPUT, EXIT_INTERRUPTED, RunOptions

DEFAULT_BENCH_OUT = "out/bench"


class _Parser(argparse.ArgumentParser):
    """argparse that reports bad arguments with exit code 2 and one line, no usage dump."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: {message} (see {self.prog} --help)\n")


def _positive(kind: type) -> Any:
    def convert(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got '{text}'") from None
        if not value > 0 or (isinstance(value, float) and not math.isfinite(value)):
            raise argparse.ArgumentTypeError(f"must be > 0, got {text}")
        return value

    return convert


def _within(kind: type, low: float, high: float) -> Any:
    """An argparse type: a ``kind`` number from ``low`` to ``high`` (both included)."""

    def convert(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got '{text}'") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be within {low:g}..{high:g}, got {text}")
        return value

    return convert


TICK_HZ = _within(float, 0.1, 1000.0)
"""Tree tick rates accepted (Hz): slower would wait for ages, faster than any physics rate."""
REALTIME = _within(float, 0.01, 1000.0)
"""Real-time factors accepted by --realtime."""


def _port_number(text: str) -> int:
    """``text`` as an integer, else the error of every port option."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a port number, got '{text}'") from None


def _port(text: str) -> int:
    value = _port_number(text)
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(
            f"{value} is not a port; use 1..65535, or 0 for any free port"
        )
    return value


def _address(text: str) -> str:
    import ipaddress

    host = text.strip()
    if host == "localhost":
        return host
    try:
        address = ipaddress.ip_address(host)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"'{text}' is not an IP address; e.g. 127.0.0.1 (this machine only) or 0.0.0.0 "
            "(every interface)"
        ) from None
    if address.version != 4:
        raise argparse.ArgumentTypeError(
            f"'{text}': the meshcat server listens on IPv4 only; use an IPv4 address such as "
            "127.0.0.1 or 0.0.0.0"
        )
    return str(address)


def _groot_port(text: str) -> int:
    """A Groot2 port: PORT serves requests, PORT+1 publishes, so at most 65534 (0: any)."""
    value = _port_number(text)
    if not 0 <= value <= 65534:
        raise argparse.ArgumentTypeError(
            f"must be a port from 1 to 65534 (PUB uses the next one), or 0 for any, got {text}")
    return value


def _bb_pair(text: str) -> tuple[str, Any]:
    """``KEY=VALUE``; VALUE is read as a JSON scalar when it is one, else kept as text."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise argparse.ArgumentTypeError(f"expected key=value, got '{text}'")
    return key.strip(), bb_value(value)


def bb_value(text: str) -> Any:
    """``1`` -> 1, ``2.5`` -> 2.5, ``true`` -> True, ``"a b"`` -> 'a b'; anything that is
    not a JSON number, boolean or string (``abc``, ``[1]``, ``null``, ``NaN``) stays the text."""
    try:
        value = json.loads(text)
    except ValueError:
        return text
    if isinstance(value, float) and not math.isfinite(value):
        return text  # json reads NaN and Infinity; keep them as text
    if isinstance(value, bool | int | float | str):
        return value
    return text


def _fault(text: str) -> Any:
    from bt_manip.run.faults import parse_fault

    try:
        return parse_fault(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(exc.problems[0].message) from None


def _add_inject(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--inject",
        action="append",
        type=_fault,
        default=[],
        metavar="FAULT",
        help="inject faults, seeded: NAME:failure:P (node NAME fails with probability P), "
        "slip:P (a held object slips), block:P (an obstacle falls on the route), "
        "pose_noise:SIGMA_M[:SIGMA_DEG] (the robot sees each object off by an offset drawn once "
        "per episode: x, y with sigma SIGMA_M metres, yaw with sigma SIGMA_DEG, default 2 deg)",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="bt-manip",
        description="Behaviour-tree tasks for mobile manipulators "
        "in PyBullet (BehaviorTree.CPP v4 XML).",
    )
    from bt_manip import __version__

    parser.add_argument("--version", action="version", version=f"bt-manip {__version__}")
    sub = parser.add_subparsers(dest="verb", metavar="VERB", parser_class=_Parser)
    sub.required = True

    run = sub.add_parser("run", help="tick a tree until it succeeds, fails or runs out of budget")
    run.add_argument("tree", type=shipped_or_given, help="BehaviorTree.CPP v4 XML file")
    run.add_argument("--world", type=shipped_or_given,
                     help="world file (YAML); without it only built-in nodes can run")
    run.add_argument("--seed", type=int, default=0, help="seed for the world's randomisation")
    run.add_argument("--tree-id", help="which BehaviorTree to run (default: main_tree_to_execute)")
    run.add_argument(
        "--models",
        action="append",
        default=[],
        metavar="MODELS.xml",
        help="TreeNodesModel files declaring extra nodes",
    )
    run.add_argument(
        "--bb",
        action="append",
        type=_bb_pair,
        default=[],
        metavar="KEY=VALUE",
        help="set a root blackboard entry before the first tick; VALUE is a JSON number, "
        'true/false or "string" when it reads as one, else text',
    )
    run.add_argument("--bb-out", metavar="FILE.json", help="write the root blackboard at the end")
    run.add_argument("--report", metavar="FILE.json", help="write the run report as JSON")
    run.add_argument("--max-ticks", type=_positive(int), help="stop after this many ticks")
    run.add_argument(
        "--max-sim-time",
        type=_positive(float),
        default=600.0,
        metavar="S",
        help="stop after this much sim time (default 600 s)",
    )
    run.add_argument(
        "--tick-hz",
        type=TICK_HZ,
        default=20.0,
        help="tree tick rate, 0.1..1000 Hz (default 20 Hz; physics runs at the world's rate)",
    )
    run.add_argument(
        "--realtime",
        type=REALTIME,
        nargs="?",
        const=1.0,
        default=None,
        metavar="FACTOR",
        help="pace the run to FACTOR x real time, 0.01..1000 (default 1)",
    )
    run.add_argument("--quiet", action="store_true", help="print only the summary")
    run.add_argument(
        "--viz",
        action="store_true",
        help="live 3D view (meshcat) and tree page; paces the run to real time",
    )
    run.add_argument(
        "--zmq-url",
        metavar="URL",
        help="draw in the meshcat server already listening at URL (implies --viz)",
    )
    run.add_argument(
        "--port",
        type=_port,
        default=None,
        help="port of the tree page (default 7080, or a free one if taken; 0 picks a free one)",
    )
    run.add_argument(
        "--bind",
        type=_address,
        default=None,
        metavar="ADDR",
        help="address the run's servers (tree page, meshcat, Groot2) listen on (default "
        "127.0.0.1; 0.0.0.0 serves every interface)",
    )
    run.add_argument(
        "--keep-serving",
        action="store_true",
        help="with --viz: keep the tree page and the 3D view up after the run, until Ctrl-C",
    )
    run.add_argument(
        "--record", metavar="FILE.html", help="write a self-contained replay page of the run"
    )
    run.add_argument(
        "--groot",
        type=_groot_port,
        nargs="?",
        const=1667,
        default=None,
        metavar="PORT",
        help="serve the run to Groot2 (default port 1667, PUB on PORT+1): live statuses, "
        "blackboards, breakpoints; 0 picks free ports",
    )
    run.add_argument(
        "--btlog",
        metavar="FILE.btlog",
        help="write the run's status changes as a Groot2 log (FileLogger2 format)",
    )
    _add_inject(run)
    add_import_flag(run)
    run.set_defaults(func=cmd_run)

    bench = sub.add_parser(
        "bench", help="run many seeded episodes and report statistics",
        description="Run many seeded episodes of a tree and report statistics. Exit codes: 0 "
        "every episode succeeded, 1 some did not, 2 bad input, 130 interrupted (the finished "
        "episodes are kept in episodes.jsonl; --resume DIR runs the rest).")
    bench.add_argument("tree", nargs="?", type=shipped_or_given,
                       help="BehaviorTree.CPP v4 XML file")
    bench.add_argument("--world", type=shipped_or_given,
                       help="world file (YAML); required unless --resume")
    bench.add_argument("--runs", type=_positive(int), default=20, help="episodes (default 20)")
    bench.add_argument("--seed", type=int, default=0, help="seed of the first episode")
    bench.add_argument("--jobs", type=_within(int, 1, 64), default=2,
                       help="worker processes, or CPUs of a local Ray instance (1..64)")
    bench.add_argument(
        "--out",
        default=DEFAULT_BENCH_OUT,
        help=f"folder for JSON, CSV and PNG output (default {DEFAULT_BENCH_OUT}; bt-manip creates "
        "at most this folder, its parent must exist)",
    )
    bench.add_argument(
        "--resume", metavar="DIR",
        help="finish the interrupted bench (or sweep) whose outputs are in DIR: run the seeds "
        "that have no episode in DIR/episodes.jsonl yet, with the same tree, world and options",
    )
    bench.add_argument(
        "--sweep", metavar="TEXT",
        help="run the bench once per value of an --inject text or bb:KEY=VALUE with {a,b,...} "
        "in place of one value, e.g. 'slip:{0,0.1,0.2}'; one folder per value in --out, and "
        "sweep.json/.csv/.png",
    )
    bench.add_argument("--backend", choices=("processes", "ray"), default="processes",
                       help="where episodes run: local worker processes (default) or Ray "
                       "(pip install 'bt-manip[ray]')")
    bench.add_argument("--address", metavar="ADDR",
                       help="with --backend ray: the cluster's address (default: start a local "
                       "instance with --jobs CPUs)")
    bench.add_argument("--tree-id")
    bench.add_argument("--models", action="append", default=[], metavar="MODELS.xml")
    bench.add_argument("--bb", action="append", type=_bb_pair, default=[], metavar="KEY=VALUE")
    bench.add_argument("--max-ticks", type=_positive(int))
    bench.add_argument("--max-sim-time", type=_positive(float), default=600.0, metavar="S")
    bench.add_argument("--tick-hz", type=TICK_HZ, default=20.0)
    bench.add_argument(
        "--btlog-failures",
        metavar="DIR",
        help="write DIR/seed-N.btlog for every episode that does not succeed (Groot2 replays it)",
    )
    _add_inject(bench)
    add_import_flag(bench)
    bench.set_defaults(func=cmd_bench)

    world = sub.add_parser("world", help="load a world and print its summary")
    world.add_argument("world", type=shipped_or_given, help="world file (YAML)")
    world.add_argument("--seed", type=int, default=0)
    world.add_argument(
        "--settle",
        type=_within(float, 0.0, 3600.0),
        default=0.0,
        metavar="S",
        help="step S seconds of sim (0..3600) with no commands and report what moved",
    )
    world.set_defaults(func=cmd_world)

    from bt_manip.bim.command import add_bim_report_verb, add_bim_verb

    add_bim_verb(sub)
    add_bim_report_verb(sub)

    from bt_manip.sim.robot_command import add_robot_verb

    add_robot_verb(sub)

    from bt_manip.examples_command import add_example_verbs

    add_example_verbs(sub)

    from bt_manip.schemas import add_schema_verb

    add_schema_verb(sub)

    try:
        from bt_manip.bt.cli_verbs import add_verbs
    except ImportError:
        pass
    else:
        add_verbs(sub)
    return parser


def _print_problems(problems: Sequence[Problem]) -> None:
    for problem in problems:
        print(problem, file=sys.stderr)


def cmd_world(args: argparse.Namespace) -> int:
    from bt_manip.sim.world import World

    with World(args.world, seed=args.seed) as world:
        print(world.summary())
        if args.settle > 0:
            before = world.snapshot()
            world.step(round(args.settle * world.rate_hz))
            after = world.snapshot()
            worst = (
                max(
                    (math.dist(before[k]["pos"], after[k]["pos"]), k) for k in before if k != "time"
                )
                if len(before) > 1
                else (0.0, "-")
            )
            print(
                f"  after {args.settle:g} s of sim with no commands, the largest drift is "
                f"{worst[0] * 1000:.3f} mm ({worst[1]})"
            )
    return 0


def episode_spec(args: argparse.Namespace) -> Any:
    from bt_manip.episode import EpisodeSpec

    options = RunOptions(
        tick_hz=args.tick_hz,
        max_sim_time=args.max_sim_time,
        max_ticks=args.max_ticks,
        realtime=getattr(args, "realtime", None),
    )
    return EpisodeSpec(
        tree=args.tree,
        world=args.world,
        seed=args.seed,
        tree_id=args.tree_id,
        models=list(args.models),
        blackboard=dict(args.bb),
        inject=list(args.inject),
        options=options,
        imports=list(args.imports),
        btlog=getattr(args, "btlog", None),
    )


def _check_outputs(args: argparse.Namespace, flags: Sequence[str]) -> None:
    """Check every output path given with ``flags`` before any work starts (exit 2 if bad)."""
    from bt_manip.outputs import check_output_file

    for flag in flags:
        value = getattr(args, flag.lstrip("-").replace("-", "_"), None)
        if value:
            check_output_file(flag, value)


def _write_outputs(writes: Sequence[tuple[str, str, Any]]) -> int:
    """Run each (flag, path, write) and report the ones that fail; 0, or 2 if any failed."""
    code = 0
    for flag, path, write in writes:
        try:
            write()
        except OSError as exc:
            print(f"{flag}: cannot write {path}: {exc.strerror or exc}", file=sys.stderr)
            code = EXIT_BAD_INPUT
    return code


def cmd_run(args: argparse.Namespace) -> int:
    from bt_manip.episode import Episode
    from bt_manip.outputs import write_text

    _check_outputs(args, ("--report", "--bb-out", "--record", "--btlog"))
    with Episode(episode_spec(args)) as episode:
        tree, world = episode.tree, episode.world
        if world is not None and not args.quiet:
            print(world.summary())
        hooks: list[Any] = [] if args.quiet else [_live_view(tree)]
        from bt_manip.viz.hooks import setup_viz

        publisher = _start_groot(args, episode)
        viz = setup_viz(args, world, tree)
        hooks += viz.hooks
        options = replace(episode.spec.options, realtime=viz.realtime)
        keep = bool(args.keep_serving and viz.viewing)
        try:
            report = episode.run(hooks, options)
        except BaseException:
            viz.close()
            raise
        finally:
            for hook in hooks:
                close = getattr(hook, "close", None)
                if hook not in viz.hooks and callable(close):
                    close()
            if publisher is not None:
                publisher.close()
        viz.close(keep_viewer=keep)
        print(report.summary())
        if report.extra.get("injected"):
            print(f"  faults injected: {len(report.extra['injected'])}")
        writes: list[tuple[str, str, Any]] = []
        if args.report:
            writes.append(("--report", args.report, lambda: report.write(args.report)))
        if args.bb_out:
            entries = json.dumps(tree.blackboard.as_dict(), indent=2, default=str) + "\n"
            writes.append(("--bb-out", args.bb_out, lambda: write_text(args.bb_out, entries)))
        status = _write_outputs(writes) or report.exit_code
        if keep:
            viz.serve_until_interrupted()
        return status


def _start_groot(args: argparse.Namespace, episode: Any) -> Any:
    """The Groot2 publisher asked for by ``--groot`` (None without it)."""
    if args.groot is None:
        return None
    from bt_manip.groot import GrootPublisher
    from bt_manip.groot.publisher import GrootError

    layout = episode.monitor().layout

    def paused(uid: int | None) -> None:
        if uid is None:
            print("groot2: breakpoint released, the run goes on", flush=True)
            return
        node = layout.nodes_by_uid[uid]
        print(f"groot2: paused at the breakpoint on {node.describe()} (uid {uid}); "
              "sim time stopped until Groot2 unlocks it", flush=True)

    bind = args.bind or "127.0.0.1"
    try:
        publisher = GrootPublisher(
            episode.monitor(), port=args.groot, bind=bind, on_pause=paused)
    except GrootError as e:
        raise InputError.single("--groot", None, str(e)) from None
    print(f"groot2: serving the tree on {bind}:{publisher.port} "
          f"(PUB {publisher.port + 1}); connect Groot2's monitor to it", flush=True)
    return publisher


def cmd_bench(args: argparse.Namespace) -> int:
    from bt_manip.bench_command import run_bench_command
    from bt_manip.outputs import make_folder

    if args.address and args.backend != "ray":
        raise InputError.single("--address", None, "only with --backend ray")
    if (not args.resume and args.out == DEFAULT_BENCH_OUT
            and not Path(DEFAULT_BENCH_OUT).parent.exists()):
        make_folder(Path(DEFAULT_BENCH_OUT).parent)  # out/, bt-manip's own default folder
    return run_bench_command(args)


def _live_view(tree: Any) -> Any:
    """A live tree view in a terminal, or status-change log lines otherwise."""
    from bt_manip.viz.console import LiveTreeView, StatusLog

    if sys.stdout.isatty():
        return LiveTreeView(tree)
    return StatusLog(tree)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``bt-manip`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "keep_serving", False) and not (args.viz or args.zmq_url):
        parser.exit(EXIT_BAD_INPUT, "--keep-serving: only with --viz (or --zmq-url)\n")
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


if __name__ == "__main__":
    sys.exit(main())
