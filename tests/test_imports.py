"""The shape of the package: no import cycle, few lazy imports, few loose modules.

These checks read ``bt_manip/`` with :mod:`ast` (nothing is imported), so they hold for the
source as written:

- no cycle among bt_manip modules, counting imports inside functions as edges and leaving out
  those under ``if TYPE_CHECKING:`` (they never run);
- at most 30 import statements of bt_manip modules inside functions (third-party imports may
  stay lazy: pybullet, ifcopenshell, matplotlib...);
- at most 15 ``.py`` files directly in ``bt_manip/``, ``__init__.py`` included;
- at most 5 ``type: ignore[misc]`` comments.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "bt_manip"

MAX_LAZY_IMPORTS = 30
MAX_TOP_LEVEL_FILES = 15
MAX_MISC_IGNORES = 5


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES: dict[str, Path] = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


@dataclass
class ImportSite:
    """One import statement of a bt_manip module: where it is and what it names."""

    module: str
    line: int
    targets: list[str] = field(default_factory=list)
    in_function: bool = False


def _known(name: str) -> str | None:
    """The longest bt_manip module that ``name`` starts with (a module or a name in one)."""
    while name:
        if name in MODULES:
            return name
        name = name.rpartition(".")[0]
    return None


def _targets(module: str, node: ast.Import | ast.ImportFrom, is_package: bool) -> list[str]:
    if isinstance(node, ast.Import):
        names = [alias.name for alias in node.names]
    else:
        if node.level:
            base = module.split(".")
            if not is_package:
                base = base[:-1]
            base = base[: len(base) - (node.level - 1)]
            stem = ".".join([*base, *([node.module] if node.module else [])])
        else:
            stem = node.module or ""
        names = [f"{stem}.{alias.name}" for alias in node.names]
    found = {_known(name) for name in names}
    return sorted(t for t in found if t is not None and t != module)


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _walk(node: ast.AST, in_function: bool) -> Iterator[tuple[ast.AST, bool]]:
    """Every node with whether it sits inside a function, skipping TYPE_CHECKING blocks."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, ast.If) and _is_type_checking(child.test):
            for other in child.orelse:
                yield from _walk_one(other, in_function)
            continue
        yield from _walk_one(child, in_function)


def _walk_one(node: ast.AST, in_function: bool) -> Iterator[tuple[ast.AST, bool]]:
    yield node, in_function
    inner = in_function or isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda)
    yield from _walk(node, inner)


def import_sites() -> list[ImportSite]:
    sites = []
    for module, path in MODULES.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node, in_function in _walk(tree, False):
            if isinstance(node, ast.Import | ast.ImportFrom):
                targets = _targets(module, node, path.name == "__init__.py")
                if targets:
                    sites.append(ImportSite(module, node.lineno, targets, in_function))
    return sites


def import_cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []
    counter = 0
    for start in sorted(edges):
        if start in index:
            continue
        work: list[tuple[str, Iterator[str]]] = [(start, iter(sorted(edges[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(edges.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    cycles.append(sorted(component))
    return cycles


def test_cycle_finder_finds_a_planted_cycle() -> None:
    edges = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": set()}
    assert import_cycles(edges) == [["a", "b", "c"]]
    assert import_cycles({"a": {"b"}, "b": set()}) == []


def test_lazy_import_counter_sees_function_bodies_and_skips_type_checking() -> None:
    source = (
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    import bt_manip.errors\n"
        "def f():\n    import bt_manip.errors\n"
    )
    tree = ast.parse(source)
    found = [
        (node.lineno, inside)
        for node, inside in _walk(tree, False)
        if isinstance(node, ast.Import) and node.names[0].name.startswith("bt_manip")
    ]
    assert found == [(5, True)]


def test_no_import_cycle() -> None:
    edges: dict[str, set[str]] = {module: set() for module in MODULES}
    for site in import_sites():
        edges[site.module].update(site.targets)
    cycles = import_cycles(edges)
    assert cycles == [], "import cycles among bt_manip modules:\n" + "\n".join(
        " <-> ".join(cycle) for cycle in cycles
    )


def test_few_imports_inside_functions() -> None:
    lazy = [site for site in import_sites() if site.in_function]
    where = "\n".join(f"  {site.module}:{site.line} -> {', '.join(site.targets)}" for site in lazy)
    assert len(lazy) <= MAX_LAZY_IMPORTS, f"{len(lazy)} imports inside functions:\n{where}"


def test_few_loose_modules() -> None:
    loose = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(loose) <= MAX_TOP_LEVEL_FILES, f"{len(loose)} files in bt_manip/: {loose}"


def test_few_misc_type_ignores() -> None:
    counts = {
        module: path.read_text(encoding="utf-8").count("type: ignore[misc]")
        for module, path in MODULES.items()
    }
    total = sum(counts.values())
    worst = sorted(((n, m) for m, n in counts.items() if n), reverse=True)[:10]
    assert total <= MAX_MISC_IGNORES, f"{total} 'type: ignore[misc]'; most in {worst}"


def test_public_names_stay_reachable_from_their_former_modules() -> None:
    """What the README, docs and user code import from before the layout still works."""
    import bt_manip.bt as bt
    import bt_manip.cli
    import bt_manip.clock
    import bt_manip.run.context
    import bt_manip.run.runner
    import bt_manip.run_context
    import bt_manip.runner
    from bt_manip.bt.registry import registry

    assert bt_manip.runner.Runner is bt_manip.run.runner.Runner
    assert bt_manip.runner.RunOptions is bt_manip.run.runner.RunOptions
    assert bt_manip.run_context.RunContext is bt_manip.run.context.RunContext
    assert callable(bt_manip.cli.main)
    assert callable(bt_manip.clock.ManualClock)
    assert callable(bt.from_py_trees) and callable(bt.load_tree)
    assert callable(registry.register)
