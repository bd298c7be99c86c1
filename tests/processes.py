"""Test helper: how the tests start the commands they interrupt."""

from __future__ import annotations

import signal


def sigint_default() -> None:
    """Run in the child before it starts (``preexec_fn``): SIGINT to its default action, so
    that the child's Python turns it into KeyboardInterrupt even when the tests run as a
    background job (a shell starts those with SIGINT ignored, and their children inherit
    that)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
