"""The run hooks behind ``bt-manip run --viz / --zmq-url / --port / --record``.

:func:`setup_viz` reads those options, starts what was asked for and returns the hooks to give
the :class:`~bt_manip.runner.Runner` and the pacing to use: a live view runs at real time
unless ``--realtime FACTOR`` says otherwise; a recording alone does not slow the run down.
A viewer that cannot start has already warned once; the run goes on headless.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bt_manip.viz.tree_page import DEFAULT_PORT


@dataclass
class VizSetup:
    """What :func:`setup_viz` started."""

    hooks: list[Any] = field(default_factory=list)
    viewing: bool = False
    realtime: float | None = None


def setup_viz(args: Any, world: Any, tree: Any, say: Callable[[str], None] = print) -> VizSetup:
    """Hooks for the ``run`` options ``viz``, ``zmq_url``, ``port``, ``record``, ``realtime``."""
    out = VizSetup(realtime=getattr(args, "realtime", None))
    title = Path(getattr(args, "tree", "") or "bt-manip").name
    if getattr(args, "viz", False) or getattr(args, "zmq_url", None):
        from bt_manip.viz.live import LiveOptions, LiveViewer

        port = getattr(args, "port", None)
        viewer = LiveViewer(
            world,
            tree,
            LiveOptions(
                zmq_url=getattr(args, "zmq_url", None),
                port=DEFAULT_PORT if port is None else port,
            ),
            title=title,
            say=say,
        )
        if viewer.start():
            out.hooks.append(viewer)
            out.viewing = True
            if out.realtime is None:
                out.realtime = 1.0
    record = getattr(args, "record", None)
    if record:
        from bt_manip.viz.recorder import Recorder, RecordOptions

        info = {
            "tree": str(getattr(args, "tree", "") or ""),
            "world": str(getattr(args, "world", "") or ""),
            "seed": getattr(args, "seed", None),
        }
        out.hooks.append(Recorder(record, world, tree, RecordOptions(title=title), info=info))
    return out
