"""Console views of a running tree, as run hooks (:class:`~bt_manip.run.hooks.RunHook`).

- :class:`LiveTreeView`: in a terminal, the whole tree redrawn in place with each node's status
  (at most ``fps`` times per wall-clock second, so it costs little on fast runs).
- :class:`StatusLog`: when output is not a terminal, one plain line per node status change,
  stamped with sim time, for logs and CI.
"""

from __future__ import annotations

import sys
import time
from typing import TYPE_CHECKING, Any, TextIO

from bt_manip.bt.display import render_status
from bt_manip.bt.status import as_status, shown
from bt_manip.run.report import NodeReport, node_reports

if TYPE_CHECKING:
    from bt_manip.run.runner import Runner


def _shown(rec: NodeReport) -> str:
    """RUNNING while running; once finished, what the node returned (not IDLE)."""
    return shown(as_status(rec.status), as_status(rec.last_status)).value


class StatusLog:
    """Prints ``[  12.350 s] path/to/node: RUNNING -> SUCCESS (reason)`` on each change."""

    def __init__(self, tree: Any, stream: TextIO | None = None) -> None:
        self.tree = tree
        self.stream = stream or sys.stdout
        self._last: dict[str, str] = {}

    def __call__(self, runner: Runner) -> None:
        for rec in node_reports(self.tree):
            before = self._last.get(rec.path, "IDLE")
            now = _shown(rec)
            if now != before:
                why = f" ({rec.reason})" if rec.reason and now == "FAILURE" else ""
                print(
                    f"[{runner.sim_time:9.3f} s] {rec.path}: {before} -> {now}{why}",
                    file=self.stream,
                )
                self._last[rec.path] = now

    def close(self) -> None:
        """Flush the stream (idempotent)."""
        self.stream.flush()


class LiveTreeView:
    """Redraws the tree with statuses in place while the run goes on (terminal only)."""

    def __init__(self, tree: Any, fps: float = 10.0) -> None:
        from rich.console import Console
        from rich.live import Live

        self.tree = tree
        self.period = 1.0 / fps
        self._next = 0.0
        self._live = Live(console=Console(), auto_refresh=False, transient=False)
        self._live.start()
        self._closed = False

    def _render(self, runner: Runner | None) -> str:
        head = f"sim time {runner.sim_time:8.2f} s, tick {runner.ticks}\n" if runner else ""
        return head + render_status(self.tree)

    def __call__(self, runner: Runner) -> None:
        now = time.monotonic()
        if now >= self._next:
            self._next = now + self.period
            from rich.text import Text

            self._live.update(Text(self._render(runner)), refresh=True)

    def close(self) -> None:
        """Draw the final statuses and stop redrawing (once)."""
        if self._closed:
            return
        self._closed = True
        from rich.text import Text

        self._live.update(Text(self._render(None)), refresh=True)
        self._live.stop()
