"""The hook through which plain py_trees behaviours enter the BT core.

The core accepts a plain ``py_trees.behaviour.Behaviour`` where it expects a bt-manip node: a
child given to a control or decorator (:func:`bt_manip.bt.node.as_bt_node`), a class given to
``registry.register``. Converting one is the job of the py_trees adapter
(:mod:`bt_manip.bt.pytrees`), which the core never imports: the adapter installs its functions
here when it is imported, and importing :mod:`bt_manip.bt` imports it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from py_trees.behaviour import Behaviour

if TYPE_CHECKING:
    from bt_manip.bt.node import BtNode


@dataclass(frozen=True)
class PyTreesAdapter:
    """What the core asks of the py_trees adapter."""

    convert_node: Callable[[Behaviour], BtNode]
    """The bt-manip node for a py_trees behaviour and everything under it."""
    leaf_class_for: Callable[[type[Behaviour]], type[BtNode]]
    """The bt-manip leaf class wrapping a py_trees behaviour class."""


_INSTALLED: list[PyTreesAdapter] = []


def install(adapter: PyTreesAdapter) -> None:
    """Make ``adapter`` the one the core asks (the adapter's package does it on import)."""
    _INSTALLED[:] = [adapter]


def adapter() -> PyTreesAdapter:
    """The installed adapter; RuntimeError when none is (``bt_manip.bt`` was not imported)."""
    if not _INSTALLED:
        raise RuntimeError("plain py_trees behaviours need the py_trees adapter: "
                           "import bt_manip.bt")
    return _INSTALLED[0]
