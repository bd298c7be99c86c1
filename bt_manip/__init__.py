"""bt-manip: behaviour-tree task orchestration for mobile manipulators in PyBullet."""

import os as _os
import sys as _sys

__version__ = "0.2.0"


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
