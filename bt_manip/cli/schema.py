"""The ``schema`` verb: list the JSON Schemas of bt-manip's output files, or print one.

``bt-manip schema`` lists them (name, title, file); ``bt-manip schema NAME`` prints one
(``run-report``, ``bench-summary``, ...) and ``bt-manip schema NAME --path`` only its file, for
a validator to read. Where the schemas are is :mod:`bt_manip.schemas`'s business.
"""

from __future__ import annotations

import argparse
import json

from bt_manip.schemas import SUFFIX, schema_folder, schema_names, schema_path


def add_schema_arguments(schema: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip schema [NAME] [--path]``."""
    schema.description = (
        "Without NAME: list the JSON Schemas (draft 2020-12) of the files bt-manip "
        "writes (the run report of run --report, bench's outputs, bim's schedule) with their "
        "files. With NAME (run-report, bench-summary, ...): print that schema, or with --path "
        "only its file.")
    schema.add_argument("name", nargs="?", metavar="NAME", help="a schema's name: run-report, ...")
    schema.add_argument("--path", action="store_true", help="print the schema's file, not its text")
    schema.set_defaults(func=cmd_schema)


VERB_ARGUMENTS = {"schema": add_schema_arguments}
"""The verbs of this module and the function that adds each one's arguments."""


def cmd_schema(args: argparse.Namespace) -> int:
    """List the schemas, or print one (its text, or its path with ``--path``)."""
    if args.name is None:
        if args.path:
            print(schema_folder())
            return 0
        for name in schema_names():
            path = schema_folder() / f"{name}{SUFFIX}"
            title = json.loads(path.read_text(encoding="utf-8")).get("title", "")
            print(f"{name:<20} {title}\n{'':<20} {path}")
        return 0
    path = schema_path(args.name)
    print(path if args.path else path.read_text(encoding="utf-8").rstrip("\n"))
    return 0
