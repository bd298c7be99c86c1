"""examples/py_trees_user.py runs a converted py_trees tree to SUCCESS and saves it as XML."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

from bt_manip.bt import load_tree_string, to_xml

ROOT = Path(__file__).resolve().parents[1]


def _example() -> ModuleType:
    spec = importlib.util.spec_from_file_location(
        "py_trees_user", ROOT / "examples" / "py_trees_user.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_py_trees_example_runs_and_round_trips() -> None:
    example = _example()
    tree, statuses = example.run(show=False)
    # warm up: 2 rounds of a 2-tick count down (4 ticks, the Repeat yields between rounds);
    # then the Parallel: Retry until 'every third' succeeds, Timer of 0.35 s at 0.1 s a tick
    assert statuses == ["RUNNING"] * 7 + ["SUCCESS"]
    assert tree.blackboard.as_dict() == {"count": 0, "warm": True}
    text = to_xml(example.from_py_trees(example.build()))
    assert '<CountDown name="count down" start="2"/>' in text
    reloaded = load_tree_string(text, context=example.TreeContext(clock=example.ManualClock()))
    clock = reloaded.context.clock
    again = []
    while not again or again[-1] == "RUNNING":
        again.append(reloaded.tick().value)
        clock.advance(0.1)
    assert again == statuses
