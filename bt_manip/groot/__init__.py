"""Groot2 support: the live monitor protocol, breakpoints and replace-hooks, .btlog files.

Groot2 (the BehaviorTree.CPP editor and monitor) attaches to a running bt-manip tree exactly as
it attaches to a BehaviorTree.CPP 4.x program:

- :mod:`~bt_manip.groot.layout` numbers the nodes (``_uid``) and names the subtree instances
  (``_fullpath``) as BT.CPP does, and writes the tree XML Groot2 asks for;
- :mod:`~bt_manip.groot.monitor` listens to every status change of a tree and stamps it with
  the run's sim time;
- :mod:`~bt_manip.groot.publisher` serves the ZMQ protocol (REP on PORT, PUB on PORT+1) from a
  thread of its own, with breakpoints that pause the tree (and so the simulation);
- :mod:`~bt_manip.groot.btlog` writes and reads FileLogger2 ``.btlog`` files.
"""

from bt_manip.groot.btlog import BtlogWriter, read_btlog
from bt_manip.groot.layout import TreeLayout, layout_of
from bt_manip.groot.monitor import TreeMonitor
from bt_manip.groot.publisher import DEFAULT_GROOT_PORT, GrootPublisher

__all__ = [
    "DEFAULT_GROOT_PORT",
    "BtlogWriter",
    "GrootPublisher",
    "TreeLayout",
    "TreeMonitor",
    "layout_of",
    "read_btlog",
]
