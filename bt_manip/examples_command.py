"""The ``demo`` and ``examples`` verbs of the command line.

``bt-manip demo [--out DIR]`` runs Scenario A (the Husky + UR3 carries a panel through the
house, headless) from any folder and writes its run report and replay page into DIR (the
current folder by default). ``bt-manip examples`` lists the shipped trees, worlds and robots;
``bt-manip examples copy DIR`` copies them into DIR for editing.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bt_manip.bundled import DEMO_TREE, DEMO_WORLD, copy_examples, list_examples
from bt_manip.sim.assets import DATA_FOLDERS, data_root

DEMO_REPORT = "husky_report.json"
DEMO_REPLAY = "husky_replay.html"


def add_example_verbs(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``bt-manip demo`` and ``bt-manip examples [copy DIR]``."""
    demo = sub.add_parser(
        "demo", help="run Scenario A headless; write its report and replay page",
        description="Run Scenario A (trees/husky_carry_wall.xml on worlds/tb3_house.yaml, "
        f"headless) and write {DEMO_REPORT} and {DEMO_REPLAY} (open it in a browser) into "
        "--out. Exit codes as for run.",
    )
    demo.add_argument("--out", default=".", metavar="DIR",
                      help="folder for the report and the replay page (default: the current "
                      "folder; bt-manip creates at most this folder, its parent must exist)")
    demo.add_argument("--seed", type=int, default=0, help="seed for the world's randomisation")
    demo.add_argument("--quiet", action="store_true", help="print only the summary")
    demo.set_defaults(func=cmd_demo)

    examples = sub.add_parser(
        "examples", help="list the shipped trees, worlds and robots, or copy them",
        description="Without a verb: list the trees, worlds and robots that ship with "
        "bt-manip (each can be named by the path shown from any folder). copy DIR: copy them "
        "into DIR to edit them.",
    )
    verbs = examples.add_subparsers(dest="examples_verb", metavar="copy",
                                    parser_class=type(examples))
    copy = verbs.add_parser("copy", help="copy trees/, worlds/ and robots/ into DIR")
    copy.add_argument("dir", metavar="DIR", help="destination folder (created if missing)")
    copy.add_argument("--force", action="store_true", help="overwrite files already there")
    copy.set_defaults(func=cmd_examples_copy)
    examples.set_defaults(func=cmd_examples_list)


def cmd_demo(args: argparse.Namespace) -> int:
    """Scenario A through ``bt-manip run``, with the shipped tree and world."""
    from bt_manip.cli import build_parser, cmd_run
    from bt_manip.outputs import check_output_folder

    root = data_root()
    out = check_output_folder("--out", args.out)
    report, replay = out / DEMO_REPORT, out / DEMO_REPLAY
    argv = ["run", str(root / DEMO_TREE), "--world", str(root / DEMO_WORLD),
            "--seed", str(args.seed), "--report", str(report), "--record", str(replay)]
    if args.quiet:
        argv.append("--quiet")
    code = cmd_run(build_parser().parse_args(argv))
    print(f"run report: {report}; replay page (open it in a browser): {replay}")
    return code


def cmd_examples_list(args: argparse.Namespace) -> int:
    """Print the shipped examples, folder by folder."""
    root = data_root()
    examples = list_examples()
    print(f"examples shipped with bt-manip, in {root}:")
    for folder in DATA_FOLDERS:
        names = [e.relative for e in examples if e.folder == folder]
        print(f"{folder}:")
        for name in names:
            print(f"  {name}")
    print("run one from any folder, e.g. bt-manip run trees/sawyer_blocks_to_bin.xml "
          "--world worlds/sawyer_table.yaml; copy them to edit: bt-manip examples copy DIR")
    return 0


def cmd_examples_copy(args: argparse.Namespace) -> int:
    """Copy the shipped folders into ``args.dir``."""
    written = copy_examples(args.dir, overwrite=args.force)
    counts = {folder: sum(1 for p in written
                          if p.relative_to(Path(args.dir)).parts[0] == folder)
              for folder in DATA_FOLDERS}
    shown = ", ".join(f"{counts[f]} files in {f}/" for f in DATA_FOLDERS)
    print(f"copied {shown} to {args.dir}")
    print(f"try: cd {args.dir} && bt-manip run {DEMO_TREE} --world {DEMO_WORLD}")
    return 0
