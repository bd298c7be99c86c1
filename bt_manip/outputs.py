"""Output paths given on the command line (``--report``, ``--bb-out``, ``--record``, ``--dot``,
bench's ``--out``): checked before any work starts, created when written.

The rule is the same for every output: bt-manip creates at most one missing folder, the
output's own (``out/`` for ``out/report.json``; the folder itself for bench's ``--out``). When
the folder above it is missing too, or a path names a file where a folder is needed (or a folder
where a file is), the check raises :class:`~bt_manip.errors.InputError` naming the flag, so the
command exits with code 2 before a run whose result could not be saved.
"""

from __future__ import annotations

import os
from pathlib import Path

from bt_manip.errors import InputError


def _bad(flag: str, message: str) -> InputError:
    return InputError.single(flag, None, message)


def _check_folder(flag: str, folder: Path, what: str) -> None:
    """``folder`` exists as a folder, or can be made with one ``mkdir`` (its parent exists)."""
    if folder.is_dir():
        if not os.access(folder, os.W_OK | os.X_OK):
            raise _bad(flag, f"cannot write in {folder}: permission denied")
        return
    if folder.exists():
        raise _bad(flag, f"{folder} is not a folder, so {what} cannot be written in it")
    parent = folder.parent
    if not parent.is_dir():
        missing = parent
        while not missing.parent.is_dir() and missing.parent != missing:
            missing = missing.parent
        if missing.exists():
            raise _bad(flag, f"{missing} is not a folder, so {what} cannot be written below it")
        raise _bad(
            flag,
            f"the folder {parent} does not exist (bt-manip creates at most the output's own "
            f"folder, {folder.name}); create {parent} first or choose another path",
        )
    if not os.access(parent, os.W_OK | os.X_OK):
        raise _bad(flag, f"cannot create {folder}: permission denied in {parent}")


EXAMPLE_NAMES = {
    "--report": "report.json",
    "--bb-out": "blackboard.json",
    "--record": "replay.html",
    "--dot": "tree.dot",
}
"""A file name to suggest, per flag, when a flag is given a folder."""


def check_output_file(flag: str, path: str | Path) -> Path:
    """Check that a file can be written at ``path`` (given with ``flag``); returns it.

    Raises InputError when ``path`` is a folder, or its folder cannot be made in one step.
    """
    out = Path(path)
    if str(path).endswith(("/", os.sep)) or out.is_dir():
        example = out / EXAMPLE_NAMES.get(flag, "output")
        raise _bad(flag, f"{path} is a directory; give a file path, e.g. {example}")
    if out.exists() and not os.access(out, os.W_OK):
        raise _bad(flag, f"cannot write {out}: permission denied")
    _check_folder(flag, out.parent, out.name)
    return out


def check_output_folder(flag: str, path: str | Path) -> Path:
    """Check that ``path`` (given with ``flag``) is a folder, or can be made in one step."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise _bad(flag, f"{out} is a file, not a folder; give a folder for the outputs")
    _check_folder(flag, out, "the outputs")
    return out


def make_folder(folder: str | Path) -> Path:
    """Create ``folder`` if it is missing (its parent must exist: one level only)."""
    out = Path(folder)
    out.mkdir(exist_ok=True)
    return out


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path``, creating its own folder if that is missing (one level)."""
    out = Path(path)
    make_folder(out.parent)
    out.write_text(text, encoding="utf-8")
