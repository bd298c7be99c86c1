"""py_trees' tools on bt-manip trees: display with live statuses, BehaviourTree and visitors."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from bt_manip.bt import Tree, from_py_trees, load_tree_string
from bt_manip.bt.pytrees.leaf import register_py_trees_behaviours

TREE = """<root BTCPP_format="4"><BehaviorTree ID="Main">
  <Sequence name="root">
    <AlwaysSuccess name="first"/>
    <Fallback name="choose">
      <SuccessEveryN name="every2" n="2"/>
      <AlwaysSuccess name="backup"/>
    </Fallback>
    <Running name="wait"/>
  </Sequence>
</BehaviorTree></root>"""


def tree() -> Tree:
    register_py_trees_behaviours()
    return load_tree_string(TREE)


def test_unicode_tree_shows_every_node_that_ran_in_the_last_tick() -> None:
    t = tree()
    t.tick()
    assert py_trees.display.unicode_tree(t.root, show_status=True) == (
        "--> root [*]\n"
        "    --> first [✓]\n"
        "    --> choose [✓]\n"
        "        --> every2 [✕] -- not yet\n"
        "        --> backup [✓]\n"
        "    --> wait [*] -- running\n")
    t.tick()  # the Sequence resumes from 'wait': the nodes of the Fallback, reset when it
    # succeeded, did not run; 'first' and 'choose' keep SUCCESS until the Sequence finishes
    assert py_trees.display.unicode_tree(t.root, show_status=True) == (
        "--> root [*]\n"
        "    --> first [✓]\n"
        "    --> choose [✓]\n"
        "        --> every2 [-] -- not yet\n"
        "        --> backup [-]\n"
        "    --> wait [*] -- running\n")
    t.halt()
    assert "[*]" not in py_trees.display.unicode_tree(t.root, show_status=True)


def test_ascii_xhtml_and_dot_views() -> None:
    t = tree()
    t.tick()
    ascii_view = py_trees.display.ascii_tree(t.root, show_status=True)
    assert "every2 [x] -- not yet" in ascii_view and "backup [o]" in ascii_view
    xhtml = py_trees.display.xhtml_tree(t.root, show_status=True)
    assert "every2" in xhtml and "not yet" in xhtml
    dot = py_trees.display.dot_tree(t.root).to_string()
    assert "every2" in dot and "choose -> backup" in dot


def test_converted_py_trees_composites_keep_their_glyphs() -> None:
    root = py_trees.composites.Parallel(
        "par", py_trees.common.ParallelPolicy.SuccessOnAll(), children=[
            py_trees.composites.Selector("sel", memory=False, children=[
                py_trees.behaviours.Failure("no"), py_trees.behaviours.Running("yes")]),
            py_trees.behaviours.Success("ok")])
    t = from_py_trees(root, builtins=False)
    t.tick()
    assert py_trees.display.unicode_tree(t.root, show_status=True) == (
        "/_/ par [*]\n"
        "    [o] sel [*]\n"
        "        --> no [✕] -- failure\n"
        "        --> yes [*] -- running\n"
        "    --> ok [✓] -- success\n")


def test_behaviour_tree_with_visitors_and_tick_handlers() -> None:
    t = tree()
    bt = py_trees.trees.BehaviourTree(t.root)
    snapshot = py_trees.visitors.SnapshotVisitor()
    bt.add_visitor(snapshot)
    bt.add_visitor(py_trees.visitors.DebugVisitor())
    seen: list[str] = []
    bt.add_pre_tick_handler(lambda tree: seen.append(f"pre {tree.count}"))
    bt.add_post_tick_handler(lambda tree: seen.append(f"post {tree.root.status.name}"))
    bt.tick()
    names = {node.id: node.name for node in t.nodes()}
    assert {names[i]: s for i, s in snapshot.visited.items()} == {
        "root": Status.RUNNING, "first": Status.SUCCESS, "choose": Status.SUCCESS,
        "every2": Status.FAILURE, "backup": Status.SUCCESS, "wait": Status.RUNNING}
    bt.tick()
    assert {names[i]: s for i, s in snapshot.visited.items()} == {
        "root": Status.RUNNING, "wait": Status.RUNNING}
    assert seen == ["pre 0", "post RUNNING", "pre 1", "post RUNNING"]
    assert t.tick_count == 2  # the BehaviourTree ticked the bt-manip tree (tickOnce)
    shown = py_trees.display.unicode_tree(
        t.root, visited=snapshot.visited, previously_visited=snapshot.previously_visited)
    assert "wait [*] -- running" in shown and "    --> backup\n" in shown


def test_display_snapshot_visitor_sees_the_root_last(capsys: object) -> None:
    t = tree()
    bt = py_trees.trees.BehaviourTree(t.root)
    visitor = py_trees.visitors.DisplaySnapshotVisitor()
    bt.add_visitor(visitor)
    bt.tick()
    assert visitor.root is t.root
