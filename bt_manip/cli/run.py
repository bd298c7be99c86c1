"""The ``run`` and ``demo`` verbs: tick a tree, with live views, Groot2 and output files.

``bt-manip run TREE.xml [--world W]`` ticks a tree (against the world's sim clock when one is
given) until it succeeds, fails or runs out of budget. ``bt-manip demo [--out DIR]`` runs
Scenario A (the Husky + UR3 carries a panel through the house, headless) from any folder and
writes its run report and replay page into DIR (the current folder by default).

Both go through :func:`run_tree`, which takes the episode and what to show, serve and write
as a :class:`RunCommand`.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

from bt_manip.bt.pytrees import values
from bt_manip.bundled import DEMO_TREE, DEMO_WORLD, shipped_or_given
from bt_manip.cli.args import (
    DEFAULT_MAX_SIM_TIME,
    DEFAULT_TICK_HZ,
    REALTIME,
    TICK_HZ,
    add_inject,
    add_localize,
    address,
    bb_pair,
    groot_port,
    port,
    positive,
)
from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.errors import InputError
from bt_manip.groot import GrootPublisher
from bt_manip.groot.publisher import GrootError
from bt_manip.outputs import check_output_file, check_output_folder, write_text
from bt_manip.plugins import add_import_flag
from bt_manip.run.hooks import RunHook
from bt_manip.run.runner import RunOptions
from bt_manip.run.status import EXIT_BAD_INPUT
from bt_manip.sim.assets import data_root
from bt_manip.viz.console import LiveTreeView, StatusLog
from bt_manip.viz.hooks import setup_viz

DEMO_REPORT = "husky_report.json"
DEMO_REPLAY = "husky_replay.html"


def add_run_arguments(run: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip run``."""
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
        type=bb_pair,
        default=[],
        metavar="KEY=VALUE",
        help="set a root blackboard entry before the first tick; VALUE is a JSON number, "
        'true/false or "string" when it reads as one, else text',
    )
    run.add_argument("--bb-out", metavar="FILE.json", help="write the root blackboard at the end")
    run.add_argument("--report", metavar="FILE.json", help="write the run report as JSON")
    run.add_argument("--max-ticks", type=positive(int), help="stop after this many ticks")
    run.add_argument(
        "--max-sim-time",
        type=positive(float),
        default=DEFAULT_MAX_SIM_TIME,
        metavar="S",
        help="stop after this much sim time (default 600 s)",
    )
    run.add_argument(
        "--tick-hz",
        type=TICK_HZ,
        default=DEFAULT_TICK_HZ,
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
        type=port,
        default=None,
        help="port of the tree page (default 7080, or a free one if taken; 0 picks a free one)",
    )
    run.add_argument(
        "--bind",
        type=address,
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
        type=groot_port,
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
    add_inject(run)
    add_localize(run)
    add_import_flag(run)
    run.set_defaults(func=cmd_run)


def add_demo_arguments(demo: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip demo``."""
    demo.description = (
        "Run Scenario A (trees/husky_carry_wall.xml on worlds/tb3_house.yaml, "
        f"headless) and write {DEMO_REPORT} and {DEMO_REPLAY} (open it in a browser) into "
        "--out. Exit codes as for run.")
    demo.add_argument("--out", default=".", metavar="DIR",
                      help="folder for the report and the replay page (default: the current "
                      "folder; bt-manip creates at most this folder, its parent must exist)")
    demo.add_argument("--seed", type=int, default=0, help="seed for the world's randomisation")
    demo.add_argument("--quiet", action="store_true", help="print only the summary")
    demo.set_defaults(func=cmd_demo)


VERB_ARGUMENTS = {"run": add_run_arguments, "demo": add_demo_arguments}
"""The verbs of this module and the function that adds each one's arguments."""


def episode_spec(args: argparse.Namespace) -> EpisodeSpec:
    """The episode that the arguments of ``run`` (or ``bench``) describe."""
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
        localize=bool(getattr(args, "localize", False)),
    )


@dataclass(frozen=True)
class RunCommand:
    """One ``bt-manip run``: the episode, and what the command prints, serves and writes."""

    spec: EpisodeSpec
    quiet: bool = False
    """Print only the summary (no live tree view, no world summary)."""
    report: str | None = None
    bb_out: str | None = None
    record: str | None = None
    viz: bool = False
    zmq_url: str | None = None
    port: int | None = None
    bind: str | None = None
    keep_serving: bool = False
    groot: int | None = None
    """Serve the run to Groot2 on this port (0: any free one); None: no Groot2."""

    # what setup_viz reads of the episode, by name
    @property
    def tree(self) -> str:
        return self.spec.tree

    @property
    def world(self) -> str | None:
        return self.spec.world

    @property
    def seed(self) -> int:
        return self.spec.seed

    @property
    def realtime(self) -> float | None:
        return self.spec.options.realtime


def cmd_run(args: argparse.Namespace) -> int:
    """``bt-manip run``: :func:`run_tree` with the parsed arguments."""
    if args.keep_serving and not (args.viz or args.zmq_url):
        print("--keep-serving: only with --viz (or --zmq-url)", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)
    return run_tree(RunCommand(
        spec=episode_spec(args), quiet=args.quiet, report=args.report, bb_out=args.bb_out,
        record=args.record, viz=args.viz, zmq_url=args.zmq_url, port=args.port,
        bind=args.bind, keep_serving=args.keep_serving, groot=args.groot))


def cmd_demo(args: argparse.Namespace) -> int:
    """Scenario A through :func:`run_tree`, with the shipped tree and world."""
    root = data_root()
    out = check_output_folder("--out", args.out)
    report, replay = out / DEMO_REPORT, out / DEMO_REPLAY
    options = RunOptions(tick_hz=DEFAULT_TICK_HZ, max_sim_time=DEFAULT_MAX_SIM_TIME)
    spec = EpisodeSpec(tree=str(root / DEMO_TREE), world=str(root / DEMO_WORLD),
                       seed=args.seed, options=options)
    code = run_tree(RunCommand(spec, quiet=args.quiet, report=str(report), record=str(replay)))
    print(f"run report: {report}; replay page (open it in a browser): {replay}")
    return code


def _check_outputs(outputs: Sequence[tuple[str, str | None]]) -> None:
    """Check every output path given, by its flag, before any work starts (exit 2 if bad)."""
    for flag, value in outputs:
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


def run_tree(command: RunCommand) -> int:
    """Run ``command``'s episode with its views, servers and output files; the exit code."""
    _check_outputs((("--report", command.report), ("--bb-out", command.bb_out),
                    ("--record", command.record), ("--btlog", command.spec.btlog)))
    with Episode(command.spec) as episode:
        tree, world = episode.tree, episode.world
        if world is not None and not command.quiet:
            print(world.summary())
        hooks: list[RunHook] = [] if command.quiet else [_live_view(tree)]
        publisher = _start_groot(command, episode)
        if publisher is not None:
            hooks.append(publisher)  # closed after the console view, before the viewer
        viz = setup_viz(command, world, tree)  # with --keep-serving the viewer outlives close()
        hooks += viz.hooks
        options = replace(episode.spec.options, realtime=viz.realtime)
        try:
            report = episode.run(hooks, options)  # the runner closes every hook
        except BaseException:
            viz.stop()  # a viewer kept for --keep-serving goes too
            raise
        print(report.summary())
        if report.extra.get("injected"):
            print(f"  faults injected: {len(report.extra['injected'])}")
        writes: list[tuple[str, str, Any]] = []
        if command.report:
            path = command.report
            writes.append(("--report", path, lambda: report.write(path)))
        if command.bb_out:
            entries = json.dumps(tree.blackboard.as_dict(_bb_value), indent=2) + "\n"
            bb_path = command.bb_out
            writes.append(("--bb-out", bb_path, lambda: write_text(bb_path, entries)))
        status = _write_outputs(writes) or report.exit_code
        if command.keep_serving and viz.viewing:
            viz.serve_until_interrupted()
        return status


def _bb_value(value: Any) -> Any:
    """``--bb-out``'s JSON for a value JSON has no type for: an object of a registered value
    type as ``to_xml`` writes it (``{"$type": NAME, "state": {...}}``), anything else as its
    text."""
    if values.is_value(value):
        try:
            return values.encode_value(value)
        except ValueError:  # attributes JSON cannot hold: its text, as for any other object
            pass
    return str(value)


def _start_groot(command: RunCommand, episode: Any) -> Any:
    """The Groot2 publisher asked for by ``--groot`` (None without it)."""
    if command.groot is None:
        return None
    layout = episode.monitor().layout

    def paused(uid: int | None) -> None:
        if uid is None:
            print("groot2: breakpoint released, the run goes on", flush=True)
            return
        node = layout.nodes_by_uid[uid]
        print(f"groot2: paused at the breakpoint on {node.describe()} (uid {uid}); "
              "sim time stopped until Groot2 unlocks it", flush=True)

    bind = command.bind or "127.0.0.1"
    try:
        publisher = GrootPublisher(
            episode.monitor(), port=command.groot, bind=bind, on_pause=paused)
    except GrootError as e:
        raise InputError.single("--groot", None, str(e)) from None
    print(f"groot2: serving the tree on {bind}:{publisher.port} "
          f"(PUB {publisher.port + 1}); connect Groot2's monitor to it", flush=True)
    return publisher


def _live_view(tree: Any) -> Any:
    """A live tree view in a terminal, or status-change log lines otherwise."""
    if sys.stdout.isatty():
        return LiveTreeView(tree)
    return StatusLog(tree)
