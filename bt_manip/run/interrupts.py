"""SIGTERM ends a run the way Ctrl-C does.

By default SIGTERM kills Python at once, so nothing cleans up: the tree is not halted and
servers started by the run (the meshcat server, the tree page) are left behind.
:func:`terminate_as_interrupt` turns SIGTERM into a KeyboardInterrupt for the duration of a
``with`` block, so the runner halts the tree, every hook is closed and the command exits with
the interrupted code (130).
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType


def _interrupt(signum: int, frame: FrameType | None) -> None:
    raise KeyboardInterrupt(f"signal {signal.Signals(signum).name}")


@contextmanager
def terminate_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM raises KeyboardInterrupt (main thread only; elsewhere it
    does nothing)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
