"""The trees py_trees' own tests tick, taken from its sdist and built again on demand.

The sdist of the installed py_trees version is downloaded with pip into the cache
(``$BT_MANIP_PY_TREES_SDIST``, else ``$XDG_CACHE_HOME/bt-manip/py_trees-sdist``) and unpacked
there once; nothing of it is kept in the repository. Its ``tests/test_*.py`` modules are
imported as the package :data:`PACKAGE` (so their relative imports of py_trees' test helpers
work), and every test (functions, their ``parametrize`` cases, ``unittest`` methods) is run
once with py_trees' ways of ticking a root hooked (``Behaviour.tick_once``,
``BehaviourTree.tick``, ``py_trees.tests.tick_tree``): each root a test ticks, in the order
of its first tick, and how many times it is ticked are recorded.

A recorded tree is built again by running its test anew until the test ticks that root for
the first time: the run stops there (:class:`Captured`) and the root, as the test's own code
built and set it up, is handed out untouched.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.metadata
import importlib.util
import inspect
import os
import subprocess
import sys
import tarfile
import tempfile
import types
import unittest
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import py_trees
import py_trees.tests

from bt_manip.cache import cache_dir

VERSION = importlib.metadata.version("py_trees")
PACKAGE = "py_trees_sdist_tests"
DOWNLOAD_TIMEOUT = 120.0


class Unavailable(Exception):
    """The sdist could not be had (no pip, no network...): the reason."""


def sdist_tests(version: str) -> Path:
    """The ``tests`` folder of py_trees' sdist ``version``, downloaded and unpacked into the
    cache the first time."""
    root = cache_dir("py_trees-sdist", "BT_MANIP_PY_TREES_SDIST")
    folder = root / f"py_trees-{version}"
    if (folder / "tests").is_dir():
        return folder / "tests"
    root.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=root) as work:
        command = [sys.executable, "-m", "pip", "download", "--no-deps", "--no-binary",
                   "py_trees", f"py_trees=={version}", "-d", work, "-q"]
        try:
            done = subprocess.run(command, capture_output=True, text=True,
                                  timeout=DOWNLOAD_TIMEOUT, check=False)
        except (OSError, subprocess.TimeoutExpired) as e:
            raise Unavailable(f"pip download of py_trees {version} failed: {e}") from e
        archives = sorted(Path(work).glob("py_trees-*.tar.gz"))
        if done.returncode != 0 or not archives:
            last = (done.stderr.strip().splitlines() or ["no archive"])[-1]
            raise Unavailable(f"pip download of py_trees {version} sdist failed: {last}")
        unpacked = Path(work) / "unpacked"
        with tarfile.open(archives[0]) as archive:
            archive.extractall(unpacked, filter="data")
        tops = [p for p in unpacked.iterdir() if (p / "tests").is_dir()]
        if not tops:
            raise Unavailable(f"py_trees {version} sdist has no tests folder")
        with contextlib.suppress(OSError):  # another process may have unpacked it meanwhile
            os.replace(tops[0], folder)
    if not (folder / "tests").is_dir():
        raise Unavailable(f"py_trees {version} sdist could not be unpacked into {root}")
    return folder / "tests"


def import_package(folder: Path) -> types.ModuleType:
    """The sdist's tests folder imported as package :data:`PACKAGE`."""
    if PACKAGE in sys.modules:
        return sys.modules[PACKAGE]
    spec = importlib.util.spec_from_file_location(
        PACKAGE, folder / "__init__.py", submodule_search_locations=[str(folder)])
    assert spec is not None and spec.loader is not None
    package = importlib.util.module_from_spec(spec)
    sys.modules[PACKAGE] = package
    spec.loader.exec_module(package)
    return package


@dataclass
class Case:
    """One test of the sdist, runnable again and again."""

    name: str
    run: Callable[[], None]
    module: types.ModuleType


def _function_cases(module: types.ModuleType, name: str, function: Any) -> Iterator[Case]:
    marks = [m for m in getattr(function, "pytestmark", []) if m.name == "parametrize"]
    if not marks:
        yield Case(name, function, module)
        return
    argnames, values = marks[0].args[:2]
    ids = marks[0].kwargs.get("ids") or [str(i) for i in range(len(values))]
    for case_id, value in zip(ids, values, strict=True):
        if isinstance(value, Iterator):  # a generator: the same items, fresh at each run
            items = list(value)
            value = None

            def run(items: list[Any] = items) -> None:
                function(**{argnames: iter(items)})
        else:
            def run(value: Any = value) -> None:
                function(**{argnames: value})
        yield Case(f"{name}[{case_id}]", run, module)


def _method_case(module: types.ModuleType, stem: str, cls: type[unittest.TestCase],
                 method: str) -> Case:
    def run() -> None:
        case = cls(method)
        case.setUp()
        try:
            getattr(case, method)()
        finally:
            case.tearDown()
            case.doCleanups()
    return Case(f"{stem}::{cls.__name__}.{method}", run, module)


def cases(folder: Path) -> tuple[list[Case], dict[str, str]]:
    """Every test of the sdist's ``test_*.py`` modules, and the modules that failed to import
    (with the error)."""
    import_package(folder)
    found: list[Case] = []
    broken: dict[str, str] = {}
    for path in sorted(folder.glob("test_*.py")):
        try:
            module = importlib.import_module(f"{PACKAGE}.{path.stem}")
        except Exception as e:  # a module needing what is not installed
            broken[path.stem] = f"{type(e).__name__}: {e}"
            continue
        for name, value in vars(module).items():
            if getattr(value, "__module__", None) != module.__name__:
                continue
            if name.startswith("test_") and inspect.isfunction(value):
                found.extend(_function_cases(module, f"{path.stem}::{name}", value))
            elif inspect.isclass(value) and issubclass(value, unittest.TestCase):
                found.extend(_method_case(module, path.stem, value, m) for m in
                             unittest.TestLoader().getTestCaseNames(value))
    return found, broken


class Captured(BaseException):
    """Raised at the first tick of the root a run looks for (a BaseException, so that no
    ``except Exception`` or ``pytest.raises(Exception)`` of a test takes it)."""

    def __init__(self, root: py_trees.behaviour.Behaviour) -> None:
        super().__init__(root.name)
        self.root = root


OnTick = Callable[[py_trees.behaviour.Behaviour, int], None]


@contextlib.contextmanager
def hooked_ticks(on_tick: OnTick) -> Iterator[None]:
    """Call ``on_tick(root, ticks)`` before each way py_trees ticks a root runs."""
    behaviour_cls = py_trees.behaviour.Behaviour
    tree_cls = py_trees.trees.BehaviourTree
    tick_once, tree_tick = behaviour_cls.tick_once, tree_cls.tick
    tick_tree = py_trees.tests.tick_tree

    def hooked_tick_once(self: py_trees.behaviour.Behaviour) -> None:
        on_tick(self, 1)
        tick_once(self)

    def hooked_tree_tick(self: py_trees.trees.BehaviourTree, *args: Any, **kwargs: Any) -> None:
        on_tick(self.root, 1)
        tree_tick(self, *args, **kwargs)

    def hooked_tick_tree(root: py_trees.behaviour.Behaviour, from_tick: int, to_tick: int,
                         *args: Any, **kwargs: Any) -> None:
        on_tick(root, to_tick - from_tick + 1)
        tick_tree(root, from_tick, to_tick, *args, **kwargs)

    behaviour_cls.tick_once = hooked_tick_once  # type: ignore[method-assign]
    tree_cls.tick = hooked_tree_tick  # type: ignore[method-assign]
    py_trees.tests.tick_tree = hooked_tick_tree
    try:
        yield
    finally:
        behaviour_cls.tick_once = tick_once  # type: ignore[method-assign]
        tree_cls.tick = tree_tick  # type: ignore[method-assign]
        py_trees.tests.tick_tree = tick_tree


@dataclass
class Recorded:
    """A root a test ticked: which test, which of its roots (by first tick), how often."""

    case: Case
    index: int
    name: str
    ticks: int

    @property
    def id(self) -> str:
        return f"{self.case.name}#{self.index}"


def quietly(run: Callable[[], None]) -> str:
    """Run ``run`` with its output dropped; the error it raised, if any ('' if none)."""
    level = py_trees.logging.level  # tests turn py_trees' debug logging on
    with open(os.devnull, "w") as sink, contextlib.redirect_stdout(sink):
        try:
            run()
        except Captured:
            raise
        except (Exception, unittest.SkipTest) as e:
            return f"{type(e).__name__}: {e}"
        finally:
            py_trees.logging.level = level
    return ""


def record(case: Case) -> tuple[list[Recorded], str]:
    """The roots ``case`` ticks, in the order of their first tick, and the test's error."""
    py_trees.tests.clear_blackboard()
    roots: list[py_trees.behaviour.Behaviour] = []
    ticks: list[int] = []

    def on_tick(root: py_trees.behaviour.Behaviour, n: int) -> None:
        for i, known in enumerate(roots):
            if known is root:
                ticks[i] += n
                return
        roots.append(root)
        ticks.append(n)

    with hooked_ticks(on_tick):
        error = quietly(case.run)
    return [Recorded(case, i, r.name, t) for i, (r, t) in enumerate(zip(roots, ticks,
                                                                          strict=True))], error


def build(recorded: Recorded) -> py_trees.behaviour.Behaviour:
    """The root ``recorded`` stands for, built again by its test, before its first tick."""
    roots: list[py_trees.behaviour.Behaviour] = []

    def on_tick(root: py_trees.behaviour.Behaviour, _n: int) -> None:
        if any(known is root for known in roots):
            return
        roots.append(root)
        if len(roots) == recorded.index + 1:
            raise Captured(root)

    with hooked_ticks(on_tick):
        try:
            error = quietly(recorded.case.run)
        except Captured as captured:
            return captured.root
    raise RuntimeError(f"{recorded.id} ticked no root this time ({error or 'no error'})")
