"""The run hooks behind ``bt-manip run --viz / --zmq-url / --port / --bind / --record /
--keep-serving``.

:func:`setup_viz` reads those options, starts what was asked for and returns the hooks to give
the :class:`~bt_manip.run.runner.Runner` (which closes them when the run ends) and the pacing to
use: a live view runs at real time unless ``--realtime FACTOR`` says otherwise; a recording
alone does not slow the run down. A meshcat viewer that cannot start has already warned once;
the run goes on headless. A tree page that cannot listen where it was asked to (``--port``
taken, ``--bind`` not an address of this machine) is bad input:
:class:`~bt_manip.errors.InputError` naming the flag. Without ``--port``, a taken default port
falls back to any free port.

With ``--keep-serving`` the live viewer outlives the run (its ``close()`` shows the end of the
run and keeps serving); :meth:`VizSetup.serve_until_interrupted` keeps it up until Ctrl-C or
SIGTERM, and :meth:`VizSetup.stop` stops it at once (when the run raised).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from bt_manip.errors import InputError
from bt_manip.viz.live import LiveOptions, LiveViewer
from bt_manip.viz.recorder import Recorder, RecordOptions
from bt_manip.viz.tree_page import DEFAULT_PORT, PortUnavailable


@dataclass
class VizSetup:
    """What :func:`setup_viz` started."""

    hooks: list[LiveViewer | Recorder] = field(default_factory=list)
    viewing: bool = False
    realtime: float | None = None
    viewer: LiveViewer | None = None
    """The live viewer, when one runs."""

    def close(self, keep_viewer: bool = False) -> None:
        """Close every hook (write the replay, stop the servers); with ``keep_viewer`` the
        live viewer stays up, showing the end of the run, else it stops even when it was
        started to keep serving. Idempotent (the runner has closed the hooks already when its
        run ended)."""
        for hook in self.hooks:
            if hook is self.viewer:
                if keep_viewer:
                    hook.show_last()
                else:
                    hook.stop()
                continue
            hook.close()

    def stop(self) -> None:
        """Stop the live viewer, kept serving or not (when the run raised)."""
        if self.viewer is not None:
            self.viewer.stop()

    def serve_until_interrupted(self, say: Callable[[str], None] = print) -> None:
        """Keep serving the live view until Ctrl-C or SIGTERM (KeyboardInterrupt), then stop
        it. Returns at once when no live view runs."""
        viewer = self.viewer
        if viewer is None or not viewer.active:
            return
        try:
            say("the run has ended; serving the live view until Ctrl-C")
            while viewer.active:
                time.sleep(0.2)
        except KeyboardInterrupt:
            pass
        finally:
            viewer.stop()


def setup_viz(args: Any, world: Any, tree: Any, say: Callable[[str], None] = print) -> VizSetup:
    """Hooks for the ``run`` options ``viz``, ``zmq_url``, ``port``, ``bind``, ``record``,
    ``realtime``."""
    out = VizSetup(realtime=getattr(args, "realtime", None))
    title = Path(getattr(args, "tree", "") or "bt-manip").name
    if getattr(args, "viz", False) or getattr(args, "zmq_url", None):
        port = getattr(args, "port", None)
        bind = getattr(args, "bind", None) or "127.0.0.1"
        options = LiveOptions(zmq_url=getattr(args, "zmq_url", None), port=port, bind=bind,
                              keep_serving=bool(getattr(args, "keep_serving", False)))
        viewer = _start_viewer(world, tree, options, title, say)
        if viewer is not None:
            out.hooks.append(viewer)
            out.viewer = viewer
            out.viewing = True
            if out.realtime is None:
                out.realtime = 1.0
    record = getattr(args, "record", None)
    if record:
        info = {
            "tree": str(getattr(args, "tree", "") or ""),
            "world": str(getattr(args, "world", "") or ""),
            "seed": getattr(args, "seed", None),
        }
        out.hooks.append(Recorder(record, world, tree, RecordOptions(title=title), info=info))
    return out


def _start_viewer(world: Any, tree: Any, options: LiveOptions, title: str,
                  say: Callable[[str], None]) -> LiveViewer | None:
    """Start the live viewer on ``options.port`` (the default one, or any free one when the
    default is taken); None when meshcat cannot run. Raises InputError for
    ``--port``/``--bind``."""
    asked = options.port
    options = replace(options, port=DEFAULT_PORT if asked is None else asked)
    while True:
        viewer = LiveViewer(world, tree, options, title=title, say=say)
        try:
            return viewer if viewer.start() else None
        except PortUnavailable as exc:
            if asked is None and options.port != 0 and exc.in_use:
                say(f"port {options.port} is in use; serving the tree page on a free port "
                    "instead")
                options = replace(options, port=0)
                continue
            raise InputError.single(exc.flag, None, exc.strerror or str(exc)) from None
