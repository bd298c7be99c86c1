"""The JSON Schemas of bt-manip's output files, and the ``schema`` verb that shows them.

Each file bt-manip writes for other programs to read (the run report of ``run --report``, the
bench outputs, ``bim``'s schedule) is documented by a JSON Schema (draft 2020-12) in
``docs/schemas/NAME.schema.json`` of a clone; a built wheel carries the same files as package
data under ``bt_manip/_data/schemas/`` (see ``setup.py``). :func:`schema_folder` is whichever of
the two this copy of bt-manip has.

``bt-manip schema`` lists them (name, title, file); ``bt-manip schema NAME`` prints one
(``run-report``, ``bench-summary``, ...) and ``bt-manip schema NAME --path`` only its file, for
a validator to read.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from bt_manip.errors import InputError
from bt_manip.sim.assets import PACKAGED_DATA, REPO_ROOT

SUFFIX = ".schema.json"
"""What each schema's file name ends with (after the schema's name)."""


def schema_folder() -> Path:
    """The folder of the JSON Schemas: an installed wheel's package data when there is one,
    else ``docs/schemas`` of the clone bt_manip was imported from."""
    packaged = PACKAGED_DATA / "schemas"
    return packaged if packaged.is_dir() else REPO_ROOT / "docs" / "schemas"


def schema_names() -> list[str]:
    """The names of the shipped schemas (``run-report``, ...), sorted."""
    return sorted(p.name.removesuffix(SUFFIX) for p in schema_folder().glob(f"*{SUFFIX}"))


def schema_path(name: str) -> Path:
    """The file of schema ``name``; InputError naming the known ones when there is none."""
    names = schema_names()
    if name not in names:
        raise InputError.single(
            "schema", None, f"no schema named '{name}'; known: {', '.join(names)}"
        )
    return schema_folder() / f"{name}{SUFFIX}"


def add_schema_verb(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``bt-manip schema [NAME] [--path]``."""
    schema = sub.add_parser(
        "schema", help="list the JSON Schemas of bt-manip's output files, or print one",
        description="Without NAME: list the JSON Schemas (draft 2020-12) of the files bt-manip "
        "writes (the run report of run --report, bench's outputs, bim's schedule) with their "
        "files. With NAME (run-report, bench-summary, ...): print that schema, or with --path "
        "only its file.",
    )
    schema.add_argument("name", nargs="?", metavar="NAME", help="a schema's name: run-report, ...")
    schema.add_argument("--path", action="store_true", help="print the schema's file, not its text")
    schema.set_defaults(func=cmd_schema)


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
