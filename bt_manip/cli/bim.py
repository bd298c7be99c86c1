"""The ``bim`` and ``bim-report`` verbs: argument parsing, then :mod:`bt_manip.bim`'s work.

``bim`` converts an IFC building and its schedule (:func:`~bt_manip.bim.convert.convert`);
``bim-report`` draws a run's as-built table on the floor plan.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bt_manip.bim import require_ifcopenshell
from bt_manip.bim.as_built import table_text
from bt_manip.bim.as_built_plot import plot, read_report
from bt_manip.bim.convert import BimOptions, convert
from bt_manip.bim.seeds import check_seeds
from bt_manip.bim.world_plot import plot_world
from bt_manip.cli.args import payload, seed_range, stock_pose
from bt_manip.errors import InputError
from bt_manip.outputs import check_output_file


def add_bim_arguments(bim: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip bim``."""
    bim.add_argument("ifc", help="building model (IFC4 or IFC2X3, STEP .ifc)")
    bim.add_argument("--out", required=True, help="folder for world.yaml and schedule.json")
    bim.add_argument(
        "--schedule", help="CSV GlobalId,start: the elements to install and their order "
        "(instead of the file's tasks; needed for IFC2X3)"
    )
    bim.add_argument("--robot", default="husky_ur3", help="robot descriptor (default husky_ur3)")
    bim.add_argument(
        "--stock", type=stock_pose, metavar="X;Y;YAW",
        help="centre and heading of the stock's stands (default: a free spot in the largest "
        "space)",
    )
    bim.add_argument("--start", metavar="SPACE", help="space the robot starts in (name)")
    bim.add_argument(
        "--payload", type=payload, metavar="KG",
        help="heaviest element the robot may carry (default: the robot's rated payload, 3 kg "
        "for husky_ur3)",
    )
    bim.add_argument(
        "--storey", metavar="NAME|INDEX",
        help="storey to build: its name, or its index (0-based, by ascending elevation); "
        "default: the ground storey (elevation nearest 0, then the most walls); a file "
        "without storeys is read whole",
    )
    bim.add_argument(
        "--skip-uninstallable", action="store_true",
        help="leave out the elements the robot cannot install (listed in schedule.json's "
        "'refused') instead of stopping",
    )
    bim.add_argument(
        "--require-install", action="store_true",
        help="exit 2 when there is nothing to install (by default the world alone is written)",
    )
    bim.add_argument("--png", metavar="FILE.png", help="draw the world's top view to FILE.png")
    bim.add_argument(
        "--seed-range", type=seed_range, metavar="FIRST:END",
        help="load the world with each seed FIRST..END-1 and check every randomised start",
    )
    bim.set_defaults(func=cmd_bim)


def add_bim_report_arguments(rep: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip bim-report``."""
    rep.add_argument("report", help="run report (run --report) of a world made by bt-manip bim")
    rep.add_argument("--png", required=True, help="image to write (PNG)")
    rep.add_argument("--world", help="world file (default: the one the report names)")
    rep.set_defaults(func=cmd_bim_report)


VERB_ARGUMENTS = {"bim": add_bim_arguments, "bim-report": add_bim_report_arguments}
"""The verbs of this module and the function that adds each one's arguments."""


def cmd_bim_report(args: argparse.Namespace) -> int:
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
    require_ifcopenshell()
    png = Path(args.png) if args.png else None
    if png is not None:
        check_output_file("--png", png)
    conversion = convert(
        BimOptions(
            ifc=Path(args.ifc),
            out=Path(args.out),
            schedule=Path(args.schedule) if args.schedule else None,
            robot=args.robot,
            stock=args.stock,
            start_space=args.start,
            payload=args.payload,
            storey=args.storey,
            skip_uninstallable=args.skip_uninstallable,
            require_install=args.require_install,
        )
    )
    print(conversion.summary())
    if png is not None:
        plot_world(conversion, png)
        print(f"wrote {png}")
    if args.seed_range is not None:
        check_seeds(conversion.world_path, args.seed_range)
        print(
            f"loaded the world with seeds {args.seed_range.start}..{args.seed_range.stop - 1}: "
            "every start is free"
        )
    return 0
