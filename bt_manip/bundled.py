"""The example trees, worlds and robots that ship with bt-manip.

They are the folders ``trees/``, ``worlds/`` and ``robots/`` of :func:`~bt_manip.sim.assets.
data_root`: the top of a clone, or the package data of an installed wheel. This module lists
them, copies them out for editing, and lets a command line name them by their relative path
(``trees/husky_carry_wall.xml``) from any folder where no such file exists.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

from bt_manip.errors import InputError
from bt_manip.outputs import check_output_folder, make_folder
from bt_manip.sim.assets import DATA_FOLDERS, data_root
from bt_manip.sim.assets import shipped_or_given as shipped_path

__all__ = [
    "DEMO_TREE",
    "DEMO_WORLD",
    "Example",
    "copy_examples",
    "list_examples",
    "shipped_or_given",
]

DEMO_TREE = "trees/husky_carry_wall.xml"
"""Scenario A's tree, run by ``bt-manip demo``."""
DEMO_WORLD = "worlds/tb3_house.yaml"
"""Scenario A's world."""

LISTED_SUFFIXES = {"trees": (".xml",), "worlds": (".yaml", ".yml"), "robots": (".yaml", ".yml")}
"""What ``bt-manip examples`` lists in each folder (the robots' URDFs and parts are copied with
them but not listed: they are not run by name)."""
MAX_COPIED_FILES = 1000
"""Files ``copy_examples`` copies at most (the shipped folders hold a few dozen)."""


@dataclass(frozen=True)
class Example:
    """One shipped file: its folder (``trees``, ``worlds``, ``robots``) and its path from the
    data root (``trees/nav2/through_poses.xml``)."""

    folder: str
    relative: str
    path: Path


def _files(folder: str) -> list[Path]:
    """Every regular file under the shipped ``folder``, sorted (caches and hidden files left
    out)."""
    top = data_root() / folder
    if not top.is_dir():
        return []
    return sorted(
        p for p in top.rglob("*")
        if p.is_file() and not any(part.startswith(".") or part == "__pycache__"
                                   for part in p.relative_to(top).parts)
    )


def list_examples() -> list[Example]:
    """The shipped trees, worlds and robot descriptors, folder by folder."""
    root = data_root()
    out: list[Example] = []
    for folder in DATA_FOLDERS:
        for path in _files(folder):
            if path.suffix in LISTED_SUFFIXES[folder]:
                out.append(Example(folder, path.relative_to(root).as_posix(), path))
    return out


def copy_examples(destination: str | Path, overwrite: bool = False) -> list[Path]:
    """Copy ``trees/``, ``worlds/`` and ``robots/`` into ``destination``; the files written.

    ``destination`` is created if it is missing (its parent must exist). A file that would be
    overwritten is an :class:`InputError` naming it, unless ``overwrite``; nothing is copied
    then. The copied worlds find the copied robots (``../robots/`` from a world).
    """
    dest = check_output_folder("examples copy", destination)
    root = data_root()
    pairs = [(src, dest / src.relative_to(root))
             for folder in DATA_FOLDERS for src in _files(folder)]
    if len(pairs) > MAX_COPIED_FILES:
        raise InputError.single(str(root), None,
                                f"more than {MAX_COPIED_FILES} files to copy; not copying")
    clashes = [target for _, target in pairs if target.exists()]
    if clashes and not overwrite:
        shown = ", ".join(str(p) for p in clashes[:5])
        more = f" and {len(clashes) - 5} more" if len(clashes) > 5 else ""
        raise InputError.single(
            str(dest), None,
            f"{len(clashes)} file(s) already there would be overwritten ({shown}{more}); "
            "choose an empty folder or add --force",
        )
    make_folder(dest)
    written = []
    for src, target in pairs:
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, target)
        written.append(target)
    return written


def shipped_or_given(text: str) -> str:
    """A tree or world path from the command line, as the file to read.

    ``text`` itself when that file exists (paths are relative to the current folder, as
    always) or when it does not name a shipped file; else, for a relative path into the shipped
    folders (``trees/husky_carry_wall.xml``, ``worlds/tb3_house.yaml``), the shipped file. So
    the README's commands run from any folder once bt-manip is installed. (The lookup is
    :func:`bt_manip.sim.assets.shipped_or_given`; ``World`` uses it too.)
    """
    return shipped_path(text)
