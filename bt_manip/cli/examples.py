"""The ``examples`` verb: list the shipped trees, worlds and robots, or copy them.

``bt-manip examples`` lists them; ``bt-manip examples copy DIR`` copies them into DIR for
editing. (``demo``, which runs one of them, is in :mod:`bt_manip.cli.run`.)
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bt_manip.bundled import DEMO_TREE, DEMO_WORLD, copy_examples, list_examples
from bt_manip.sim.assets import DATA_FOLDERS, data_root


def add_examples_arguments(examples: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip examples [copy DIR]``."""
    examples.description = (
        "Without a verb: list the trees, worlds and robots that ship with "
        "bt-manip (each can be named by the path shown from any folder). copy DIR: copy them "
        "into DIR to edit them.")
    verbs = examples.add_subparsers(dest="examples_verb", metavar="copy",
                                    parser_class=type(examples))
    copy = verbs.add_parser("copy", help="copy trees/, worlds/ and robots/ into DIR")
    copy.add_argument("dir", metavar="DIR", help="destination folder (created if missing)")
    copy.add_argument("--force", action="store_true", help="overwrite files already there")
    copy.set_defaults(func=cmd_examples_copy)
    examples.set_defaults(func=cmd_examples_list)


VERB_ARGUMENTS = {"examples": add_examples_arguments}
"""The verbs of this module and the function that adds each one's arguments."""


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
