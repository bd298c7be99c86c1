"""BehaviorTree.CPP 4.8.2's tree and Groot2 publisher in a process of their own.

``python btcpp_worker.py TREE.xml PORT``: builds the tree (entry ``n`` = 0 first), serves it
on PORT, prints ``ready``, then ticks once (``tickOnce``) per ``tick`` line read and prints
``ticked``. A separate process because behaviortreepy keeps Python's lock while a
breakpoint holds its tick, which would stop every Python thread of a shared process.
"""

from __future__ import annotations

import sys
from pathlib import Path

import behaviortreepy as b


def main() -> None:
    factory = b.BehaviorTreeFactory()
    factory.register_behavior_tree_from_text(Path(sys.argv[1]).read_text())
    blackboard = b.Blackboard.create()
    blackboard.set_int("n", 0)
    tree = factory.create_tree("MainTree", blackboard)
    publisher = b.Groot2Publisher(tree, int(sys.argv[2]))
    print("ready", flush=True)
    for line in sys.stdin:
        if line.strip() != "tick":
            break
        tree.tick_once()
        print("ticked", flush=True)
    del publisher


if __name__ == "__main__":
    main()
