"""The Python examples build the same trees as the XML files of the scenarios."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

import pytest

import bt_manip.behaviours  # noqa: F401  (registers the robot nodes)
from bt_manip.bt import BtNode, SubTree, load_tree, load_tree_string, to_xml
from bt_manip.bt.ports import Literal

ROOT = Path(__file__).resolve().parents[1]


def _example(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _value(node: BtNode, port: str) -> object:
    """What a port is bound to: the converted literal (so 70 and 70.0 agree), or its text."""
    binding = node.bindings.get(port)
    if isinstance(binding, Literal) and isinstance(binding.value, int | float | bool | list):
        return tuple(binding.value) if isinstance(binding.value, list) else binding.value
    return node.attribute_texts[port]


def shape(node: BtNode) -> tuple:  # type: ignore[type-arg]
    sub = (node.tree_id,) if isinstance(node, SubTree) else ()
    ports = tuple(sorted((k, _value(node, k)) for k in node.attribute_texts))
    return (node.NODE_ID, node.name, *sub, ports, tuple(shape(c) for c in node.bt_children()))


@pytest.mark.parametrize("name", ["sawyer_blocks_to_bin", "husky_carry_wall"])
def test_python_example_equals_the_xml_tree(name: str) -> None:
    built = _example(name).build()
    from_file = load_tree(str(ROOT / "trees" / f"{name}.xml"))
    assert shape(built.root) == shape(from_file.root)
    # and its XML loads back to the same tree
    assert shape(load_tree_string(to_xml(built)).root) == shape(from_file.root)


def test_run_a_tree_stacks_block_1_on_block_0() -> None:
    """examples/run_a_tree.py runs trees/sawyer_stack_two.xml through bt_manip.run_tree: the
    tree succeeds and block_1 ends resting on block_0 (centred within 1 cm, one block height
    above it)."""
    report, positions = _example("run_a_tree").stack(seed=3)
    assert report.status.value == "SUCCESS", report.reason
    (x0, y0, z0), (x1, y1, z1) = positions["block_0"], positions["block_1"]
    assert abs(x1 - x0) < 0.01 and abs(y1 - y0) < 0.01
    assert abs((z1 - z0) - 0.05) < 0.005
    assert abs(z0 - 0.7725) < 0.005  # block_0 still on the table
