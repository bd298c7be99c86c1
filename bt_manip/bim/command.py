"""The ``bim`` verb of the command line: argument parsing, then :func:`convert`."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from bt_manip.errors import InputError

MAX_PAYLOAD = 10000.0
"""Largest ``--payload`` (kg)."""
MAX_SEEDS = 1000
"""Seeds ``--seed-range`` checks at most."""


def _stock(text: str) -> tuple[float, float, float]:
    parts = text.split(";")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"expected X;Y;YAW (metres, radians), got '{text}'")
    return values  # type: ignore[return-value]


def _payload(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0.0 < value <= MAX_PAYLOAD):
        raise argparse.ArgumentTypeError(
            f"expected a mass in (0, {MAX_PAYLOAD:g}] kg, got '{text}'"
        )
    return value


def _seed_range(text: str) -> range:
    low, sep, high = text.partition(":")
    try:
        seeds = range(int(low), int(high)) if sep else range(int(low), int(low) + 1)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected FIRST:END (END excluded), got '{text}'"
        ) from None
    if not 0 < len(seeds) <= MAX_SEEDS:
        raise argparse.ArgumentTypeError(f"give 1..{MAX_SEEDS} seeds, got '{text}'")
    return seeds


def add_bim_verb(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``bt-manip bim``."""
    bim = sub.add_parser(
        "bim",
        help="an IFC building model and its schedule to a world and the elements to install",
    )
    bim.add_argument("ifc", help="building model (IFC4 or IFC2X3, STEP .ifc)")
    bim.add_argument("--out", required=True, help="folder for world.yaml and schedule.json")
    bim.add_argument(
        "--schedule", help="CSV GlobalId,start: the elements to install and their order "
        "(instead of the file's tasks; needed for IFC2X3)"
    )
    bim.add_argument("--robot", default="husky_ur3", help="robot descriptor (default husky_ur3)")
    bim.add_argument(
        "--stock", type=_stock, metavar="X;Y;YAW",
        help="centre and heading of the stock's stands (default: a free spot in the largest "
        "space)",
    )
    bim.add_argument("--start", metavar="SPACE", help="space the robot starts in (name)")
    bim.add_argument(
        "--payload", type=_payload, metavar="KG",
        help="heaviest element the robot may carry (default: the robot's rated payload, 3 kg "
        "for husky_ur3)",
    )
    bim.add_argument(
        "--seed-range", type=_seed_range, metavar="FIRST:END",
        help="load the world with each seed FIRST..END-1 and check every randomised start",
    )
    bim.set_defaults(func=cmd_bim)


def add_bim_report_verb(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``bt-manip bim-report``."""
    rep = sub.add_parser(
        "bim-report",
        help="the floor plan of an installation run, elements coloured by their deviation",
    )
    rep.add_argument("report", help="run report (run --report) of a world made by bt-manip bim")
    rep.add_argument("--png", required=True, help="image to write (PNG)")
    rep.add_argument("--world", help="world file (default: the one the report names)")
    rep.set_defaults(func=cmd_bim_report)


def cmd_bim_report(args: argparse.Namespace) -> int:
    from bt_manip.bim.as_built import table_text
    from bt_manip.bim.as_built_plot import plot, read_report
    from bt_manip.outputs import check_output_file

    report = read_report(Path(args.report))
    world = Path(args.world or str(report.get("world") or ""))
    if not world.is_file():
        raise InputError.single(
            "--world" if args.world else args.report, None,
            f"world file '{world}' not found; give it with --world",
        )
    out = Path(args.png)
    check_output_file("--png", out)
    plot(report, world, out)
    print(table_text(report["as_built"]))
    print(f"wrote {out}")
    return 0


def cmd_bim(args: argparse.Namespace) -> int:
    from bt_manip.bim import require_ifcopenshell

    require_ifcopenshell()
    from bt_manip.bim.convert import BimOptions, convert

    conversion = convert(
        BimOptions(
            ifc=Path(args.ifc),
            out=Path(args.out),
            schedule=Path(args.schedule) if args.schedule else None,
            robot=args.robot,
            stock=args.stock,
            start_space=args.start,
            payload=args.payload,
        )
    )
    print(conversion.summary())
    if args.seed_range is not None:
        check_seeds(conversion.world_path, args.seed_range)
        print(
            f"loaded the world with seeds {args.seed_range.start}..{args.seed_range.stop - 1}: "
            "every start is free"
        )
    return 0


def check_seeds(world_path: Path, seeds: range) -> None:
    """Load the world with each seed (PyBullet): the randomised starts must not overlap."""
    from bt_manip.sim.world import World

    problems = []
    for seed in seeds:
        try:
            with World(world_path, seed=seed):
                pass
        except InputError as exc:
            problems += [
                type(p)(p.file, p.line, f"seed {seed}: {p.message}", p.column) for p in exc.problems
            ]
    if problems:
        raise InputError(problems)
