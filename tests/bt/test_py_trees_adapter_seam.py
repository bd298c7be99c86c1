"""The BT core and its py_trees adapter: the core never imports the adapter
(``bt_manip.bt.pytrees``); the adapter installs itself through ``bt_manip.bt.py_trees_hook``,
which the core asks when it meets a plain py_trees behaviour."""

from __future__ import annotations

import ast
from pathlib import Path

import py_trees
import pytest

import bt_manip.bt
from bt_manip.bt import py_trees_hook, registry
from bt_manip.bt.controls import Sequence
from bt_manip.bt.pytrees import convert_node, leaf_class_for
from bt_manip.bt.pytrees.leaf import PyTreesLeaf

BT = Path(bt_manip.bt.__file__).parent
ADAPTER = "bt_manip.bt.pytrees"


def _imported_modules(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def test_core_modules_never_import_the_adapter() -> None:
    core = [p for p in BT.glob("*.py") if p.name != "__init__.py"]
    assert len(core) > 10
    offenders = {
        p.name: sorted(n for n in _imported_modules(p)
                       if n == ADAPTER or n.startswith(ADAPTER + "."))
        for p in core
    }
    assert {name: found for name, found in offenders.items() if found} == {}


def test_importing_bt_installs_the_adapter() -> None:
    adapter = py_trees_hook.adapter()
    assert adapter.convert_node is convert_node
    assert adapter.leaf_class_for is leaf_class_for


def test_core_asks_the_hook_for_plain_behaviours() -> None:
    sequence = Sequence(children=[py_trees.behaviours.Success(name="ok")])
    (child,) = sequence.bt_children()
    assert isinstance(child, PyTreesLeaf) and child.name == "ok"

    class Seam(py_trees.behaviour.Behaviour):
        def update(self) -> py_trees.common.Status:
            return py_trees.common.Status.SUCCESS

    assert registry.register(Seam) is Seam
    try:
        registered = registry.get("Seam")
        assert registered is not None and issubclass(registered, PyTreesLeaf)
    finally:
        registry.unregister("Seam")


def test_without_an_adapter_the_core_says_what_is_missing(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(py_trees_hook, "_INSTALLED", [])
    with pytest.raises(RuntimeError, match="py_trees adapter"):
        Sequence(children=[py_trees.behaviours.Success(name="ok")])
