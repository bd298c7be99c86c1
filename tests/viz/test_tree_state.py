"""What the pages show for each node: its status while it runs, then what it last returned."""

from __future__ import annotations

import py_trees

from bt_manip.bt import load_tree_string
from bt_manip.viz.tree_state import STATUS_NAMES, TreeWatcher, shown_status

XML = """<root BTCPP_format="4"><BehaviorTree ID="M">
  <Sequence name="mission">
    <Fallback name="recover">
      <AlwaysFailure name="plan_a"/>
      <Sequence name="plan_b">
        <Timeout name="quick" msec="30"><Sleep name="slow" msec="5000"/></Timeout>
      </Sequence>
    </Fallback>
  </Sequence>
</BehaviorTree></root>"""


def _shown(watcher: TreeWatcher) -> dict[str, str]:
    return {n.name: STATUS_NAMES[s] for n, s in zip(watcher.nodes, watcher.statuses, strict=True)}


def test_a_failed_leaf_shows_failure_beside_its_failed_parents() -> None:
    tree = load_tree_string(XML)
    watcher = TreeWatcher(tree)
    tree.tick()
    watcher.update()
    running = _shown(watcher)
    # plan_a failed at once; BehaviorTree.CPP already reset it to IDLE, the page keeps FAILURE
    assert running["plan_a"] == "FAILURE" and running["slow"] == "RUNNING"
    assert tree.tick_while_running().name == "FAILURE"
    watcher.update()
    end = _shown(watcher)
    assert end["mission"] == "FAILURE" and end["recover"] == "FAILURE"
    assert end["plan_a"] == "FAILURE" and end["quick"] == "FAILURE"
    assert end["slow"] == "IDLE"  # halted by the Timeout while RUNNING: it returned nothing


class _Fails(py_trees.behaviour.Behaviour):
    def update(self) -> py_trees.common.Status:
        return py_trees.common.Status.FAILURE


class _Plain:
    """A py_trees tree without node records: the watcher remembers results itself."""

    def __init__(self) -> None:
        self.root = py_trees.composites.Selector(
            "recover", memory=True,
            children=[_Fails("plan_a"), py_trees.behaviours.Running("plan_b")],
        )


def test_a_plain_py_trees_tree_keeps_the_last_result_it_was_seen_with() -> None:
    tree = _Plain()
    watcher = TreeWatcher(tree)
    tree.root.tick_once()
    watcher.update()
    assert _shown(watcher)["plan_a"] == "FAILURE"
    tree.root.children[0].stop(py_trees.common.Status.INVALID)  # reset, as a parent does
    watcher.update()
    assert _shown(watcher)["plan_a"] == "FAILURE"
    tree.root.stop(py_trees.common.Status.INVALID)  # plan_b halted while RUNNING
    watcher.update()
    assert _shown(watcher)["plan_b"] == "IDLE"


def test_shown_status() -> None:
    idle, running, success, failure = 0, 1, 2, 3
    assert shown_status(idle, failure) == failure
    assert shown_status(idle, success) == success
    assert shown_status(idle, running) == idle
    assert shown_status(running, failure) == running
