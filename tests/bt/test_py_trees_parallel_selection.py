"""A py_trees Parallel whose SuccessOnSelected policy selects what is not its child.

py_trees builds such a parallel and raises at its every tick (``RuntimeError`` naming the
behaviours); the converted tree does the same, naming the node, and ``to_xml`` refuses to
write a selection XML cannot hold.
"""

from __future__ import annotations

import py_trees
import pytest

from bt_manip.bt import from_py_trees, to_xml
from bt_manip.bt.node import TreeRuntimeError
from bt_manip.bt.pytrees.composites import PyTreesParallel

Running = py_trees.behaviours.Running


def parallel(selected_outside: bool) -> py_trees.composites.Parallel:
    first, second, outside = Running(name="first"), Running(name="second"), Running("outside")
    selected = [first, outside] if selected_outside else [second]
    policy = py_trees.common.ParallelPolicy.SuccessOnSelected(children=selected)
    return py_trees.composites.Parallel("both", policy=policy, children=[first, second])


@pytest.mark.parametrize("builtins", [True, False])
def test_selection_outside_the_parallel_raises_at_each_tick(builtins: bool) -> None:
    root = parallel(selected_outside=True)
    with pytest.raises(RuntimeError, match=r"not children of this parallel \['outside'\]"):
        root.tick_once()  # py_trees' own behaviour, which the conversion keeps
    tree = from_py_trees(parallel(selected_outside=True), builtins=builtins)
    for _ in range(2):
        with pytest.raises(TreeRuntimeError,
                           match=r"PyTreesParallel 'both'.*not children of this parallel "
                                 r"\['outside'\]"):
            tree.tick()
    node = tree.root
    assert isinstance(node, PyTreesParallel)
    assert [c.name for c in node.policy.children] == ["first", "outside"]
    assert node.policy.children[0] is node.children[0]  # the converted child
    with pytest.raises(ValueError, match=r"argument 'selected'.*\['outside'\]"):
        to_xml(tree)


def test_selection_of_its_own_children_is_written_by_index() -> None:
    tree = from_py_trees(parallel(selected_outside=False))
    assert 'selected="1"' in to_xml(tree)
