"""The JSON Schemas of bt-manip's output files: where they are, by name.

Each file bt-manip writes for other programs to read (the run report of ``run --report``, the
bench outputs, ``bim``'s schedule) is documented by a JSON Schema (draft 2020-12) in
``docs/schemas/NAME.schema.json`` of a clone; a built wheel carries the same files as package
data under ``bt_manip/_data/schemas/`` (see ``setup.py``). :func:`schema_folder` is whichever of
the two this copy of bt-manip has.

The ``schema`` verb that lists and prints them is :mod:`bt_manip.cli.schema`.
"""

from __future__ import annotations

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
