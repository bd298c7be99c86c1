"""``bt-manip convert FILE.xml [-o OUT.xml]``: a BehaviorTree.CPP v3 file in its v4 form
(:mod:`bt_manip.bt.v3_convert`).

The v4 text goes to ``OUT.xml`` (never over ``FILE.xml``) or to stdout; stderr gets one line
per rewrite, ``FILE:LINE: SequenceStar -> SequenceWithMemory``. Exit 0 once written, 2 with
``FILE:LINE: problem`` for input that cannot be read or is not well-formed XML.
"""

from __future__ import annotations

import argparse
import os
import sys

from bt_manip.bt.v3_convert import ConvertError, convert_v3
from bt_manip.bt.xml_parse import MAX_BYTES
from bt_manip.errors import InputError
from bt_manip.input_files import read_bounded
from bt_manip.run.status import EXIT_BAD_INPUT


def add_convert_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip convert FILE.xml [-o OUT.xml]``."""
    parser.description = (
        "Write a BehaviorTree.CPP v3 file in its v4 form, to stdout or to -o OUT.xml (never "
        "over FILE.xml). One stderr line per rewrite: FILE:LINE: what was rewritten.")
    parser.add_argument("file", metavar="FILE.xml", help="BehaviorTree.CPP v3 XML file")
    parser.add_argument("-o", "--output", metavar="OUT.xml", default=None,
                        help="write the v4 form here instead of stdout (never over FILE.xml)")
    parser.set_defaults(func=cmd_convert)


VERB_ARGUMENTS = {"convert": add_convert_arguments}
"""The verbs of this module and the function that adds each one's arguments."""


def cmd_convert(args: argparse.Namespace) -> int:
    """Convert ``args.file``; 0 when written, 2 with ``FILE:LINE: problem`` otherwise."""
    path = str(args.file)
    try:
        text = read_bounded(path, MAX_BYTES, "file").decode("utf-8")
    except InputError as exc:
        for problem in exc.problems:
            print(str(problem), file=sys.stderr)
        return EXIT_BAD_INPUT
    except UnicodeDecodeError as exc:
        line = exc.object[:exc.start].count(b"\n") + 1
        print(f"{path}:{line}: not UTF-8 text", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        v4, rewrites = convert_v3(text)
    except ConvertError as exc:
        print(f"{path}:{exc.line}: malformed XML: {exc.message}", file=sys.stderr)
        return EXIT_BAD_INPUT
    out = args.output
    if out is not None and os.path.exists(out) and os.path.samefile(out, path):
        print(f"{path}: -o names the input file; convert never overwrites it", file=sys.stderr)
        return EXIT_BAD_INPUT
    for line, change in rewrites:
        print(f"{path}:{line}: {change}", file=sys.stderr)
    if out is None:
        sys.stdout.write(v4)
        return 0
    try:
        with open(out, "w", encoding="utf-8") as f:
            f.write(v4)
    except OSError as exc:
        print(f"{out}: cannot write: {exc.strerror}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return 0
