"""The py_trees adapter: py_trees behaviours, composites and whole trees as bt-manip nodes.

- :mod:`~bt_manip.bt.pytrees.leaf`: a py_trees behaviour (class or object) as a bt-manip leaf,
  with its constructor arguments (:mod:`~bt_manip.bt.pytrees.arguments`) and blackboard clients
  (:mod:`~bt_manip.bt.pytrees.storage`);
- :mod:`~bt_manip.bt.pytrees.composites`: py_trees' composites and decorators with py_trees'
  semantics;
- :mod:`~bt_manip.bt.pytrees.convert`: ``from_py_trees``, a whole py_trees tree as a bt-manip
  tree.

The BT core (:mod:`bt_manip.bt.node`, the registry, controls...) never imports this package:
importing it installs the conversions the core asks for (:mod:`bt_manip.bt.py_trees_hook`).
"""

from bt_manip.bt.py_trees_hook import PyTreesAdapter, install
from bt_manip.bt.pytrees.convert import convert_node, from_py_trees
from bt_manip.bt.pytrees.leaf import leaf_class_for, register_py_trees_behaviours

install(PyTreesAdapter(convert_node=convert_node, leaf_class_for=leaf_class_for))

__all__ = ["convert_node", "from_py_trees", "leaf_class_for", "register_py_trees_behaviours"]
