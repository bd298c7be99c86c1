"""bt-manip: behaviour-tree task orchestration for mobile manipulators in PyBullet.

From Python, the two entry points are::

    import bt_manip

    report = bt_manip.run_tree("trees/sawyer_stack_two.xml", world="worlds/sawyer_table.yaml",
                               seed=3)
    print(report.status, report.reason)

    tree = bt_manip.load_tree("trees/sawyer_blocks_to_bin.xml")   # every shipped node known

:func:`run_tree` runs a tree file on a world as ``bt-manip run`` does and returns the run
report; :func:`load_tree` loads one with the robot behaviours and Nav2's nodes registered (the
lower-level :func:`bt_manip.bt.load_tree` knows only the nodes registered so far). Both find the
shipped trees and worlds by their relative paths from any folder, as the command line does, and
so does :class:`bt_manip.sim.world.World`. Importing ``bt_manip`` stays cheap: the two are
loaded (with the simulator) on first use.
"""

import os as _os
import sys as _sys
from typing import TYPE_CHECKING
from typing import Any as _Any

if TYPE_CHECKING:  # what the first use of each name imports
    from bt_manip.episode import load_tree_with_nodes as load_tree
    from bt_manip.episode import run_tree

__version__ = "0.2.0"

__all__ = ["__version__", "load_tree", "run_tree"]

_ENTRY_POINTS = {"load_tree": "load_tree_with_nodes", "run_tree": "run_tree"}
"""The names of this package that :mod:`bt_manip.episode` provides, loaded on first use."""


def __getattr__(name: str) -> _Any:
    """``bt_manip.load_tree`` and ``bt_manip.run_tree``, imported on first use."""
    if name in _ENTRY_POINTS:
        from bt_manip import episode

        value = getattr(episode, _ENTRY_POINTS[name])
        globals()[name] = value
        return value
    raise AttributeError(f"module 'bt_manip' has no attribute '{name}'")


def _import_pybullet_quietly() -> None:
    """Import pybullet once with stderr muted: its C module prints a build banner on import."""
    if "pybullet" in _sys.modules:
        return
    try:
        _sys.stderr.flush()
        saved = _os.dup(2)
    except (OSError, ValueError):
        return
    devnull = _os.open(_os.devnull, _os.O_WRONLY)
    _os.dup2(devnull, 2)
    try:
        import pybullet  # noqa: F401
    except ImportError:
        pass
    finally:
        _os.dup2(saved, 2)
        _os.close(saved)
        _os.close(devnull)


_import_pybullet_quietly()
