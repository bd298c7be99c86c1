"""User modules that register nodes: ``--import MODULE`` of run, bench, validate, show, nodes.

A node class registers itself when its module is imported (``@registry.register``). A module is
named like Python's ``import`` names it (``my_nodes``, ``lab.nodes``: searched in the working
directory first, as ``python -m`` does) or by its file (``nodes/grasping.py``). A module that
cannot be found or raises while importing is bad input: a problem naming the flag, and where
the error is when it is a syntax error or an exception in the module's own code.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import os
import sys
import traceback
import zlib
from collections.abc import Iterable
from pathlib import Path

from bt_manip.errors import Problem

FLAG = "--import"


def add_import_flag(parser: argparse.ArgumentParser) -> None:
    """``--import MODULE`` (repeatable): a user's module that registers nodes."""
    parser.add_argument(
        "--import",
        dest="imports",
        action="append",
        default=[],
        metavar="MODULE",
        help="import MODULE (a module name or a .py file) to register its nodes; repeatable",
    )


def import_modules(names: Iterable[str]) -> list[Problem]:
    """Import each module of ``names``; one problem for each that fails."""
    problems = []
    for name in names:
        problem = import_module(name)
        if problem is not None:
            problems.append(problem)
    return problems


def import_module(name: str) -> Problem | None:
    """Import ``name`` (a module name or a ``.py`` file); a problem if that fails."""
    if not name.strip():
        return Problem(FLAG, None, "needs a module name or a .py file, got ''")
    by_file = name.endswith(".py") or os.sep in name or "/" in name
    try:
        if by_file:
            _import_file(Path(name))
        else:
            cwd = os.getcwd()
            if cwd not in sys.path:
                sys.path.insert(0, cwd)
            importlib.import_module(name)
    except _NotFound as exc:
        return Problem(FLAG, None, str(exc))
    except ModuleNotFoundError as exc:
        if exc.name is not None and (exc.name == name or name.startswith(exc.name + ".")):
            return Problem(FLAG, None, f"no module named '{name}' (looked in {os.getcwd()} "
                           "and the installed packages); give a module name or a .py file")
        return _failure(name, exc)
    except SyntaxError as exc:
        where = f"{exc.filename}:{exc.lineno}: " if exc.filename else ""
        return Problem(FLAG, None, f"{where}syntax error in module '{name}': {exc.msg}")
    except Exception as exc:  # any error in the user's module is bad input
        return _failure(name, exc)
    return None


class _NotFound(Exception):
    pass


def _import_file(path: Path) -> None:
    if not path.is_file():
        what = "is a directory" if path.is_dir() else "not found"
        raise _NotFound(f"{path} {what}; give a Python file (.py) or a module name")
    real = path.resolve()
    module_name = f"bt_manip_user_{real.stem}_{zlib.crc32(str(real).encode()):08x}"
    if module_name in sys.modules:
        return
    spec = importlib.util.spec_from_file_location(module_name, real)
    if spec is None or spec.loader is None:
        raise _NotFound(f"{path} cannot be imported as a Python module")
    module = importlib.util.module_from_spec(spec)
    sys.modules[module_name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[module_name]
        raise


def _failure(name: str, exc: BaseException) -> Problem:
    """The error of a module that raised while importing, at the frame that raised it."""
    frames = [f for f in traceback.extract_tb(exc.__traceback__)
              if "importlib" not in f.filename and not f.filename.startswith("<frozen")
              and f.filename != __file__]
    here = frames[-1] if frames else None
    where = f"{here.filename}:{here.lineno}: " if here is not None else ""
    return Problem(FLAG, None, f"{where}importing '{name}' raised {type(exc).__name__}: {exc}")
