"""The parent side of the oracle: a long-lived worker process running BehaviorTree.CPP.

BT.CPP prints on stdout and can abort its process (a throwing ``_onHalted`` in a tree's
destructor), so it runs in :mod:`oracle_worker`, fed one case at a time. A worker that dies or
hangs is replaced; the case it was running gets a ``crashed`` or ``hung`` result.
"""

from __future__ import annotations

import contextlib
import json
import os
import select
import subprocess
import sys
from pathlib import Path
from typing import Any

from differential.spec import Case

WORKER = Path(__file__).with_name("oracle_worker.py")


def oracle_available() -> bool:
    try:
        import behaviortreepy  # noqa: F401
    except ImportError:
        return False
    return True


class Oracle:
    """Runs cases on BehaviorTree.CPP in a worker process; use as a context manager."""

    def __init__(self, timeout: float = 10.0) -> None:
        self.timeout = timeout
        self.proc: subprocess.Popen[bytes] | None = None
        self.restarts = 0
        self._buffer = b""
        self._timed_out = False

    def __enter__(self) -> Oracle:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _start(self) -> subprocess.Popen[bytes]:
        if self.proc is None or self.proc.poll() is not None:
            if self.proc is not None:  # it died since the last case
                self.restarts += 1
            self.proc = subprocess.Popen(
                [sys.executable, str(WORKER)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                stderr=subprocess.DEVNULL, cwd=str(WORKER.parent))
            self._buffer = b""
        return self.proc

    def close(self) -> None:
        if self.proc is not None:
            if self.proc.poll() is None:
                assert self.proc.stdin is not None
                self.proc.stdin.close()
                try:
                    self.proc.wait(timeout=5)
                except subprocess.TimeoutExpired:
                    self.proc.kill()
                    self.proc.wait()
            self.proc = None

    def _kill(self) -> None:
        if self.proc is not None:
            self.proc.kill()
            self.proc.wait()
            self.proc = None
            self.restarts += 1

    def abort_worker(self) -> None:
        """Make the worker abort (as a tree's destructor can); for testing the restart."""
        proc = self._start()
        assert proc.stdin is not None
        proc.stdin.write(b'{"abort": true}\n')
        proc.stdin.flush()
        proc.wait()

    def _read_line(self) -> bytes | None:
        """One line from the worker, or None when it died or did not answer in time."""
        proc = self.proc
        assert proc is not None and proc.stdout is not None
        fd = proc.stdout.fileno()
        self._timed_out = False
        while b"\n" not in self._buffer:
            ready, _, _ = select.select([fd], [], [], self.timeout)
            if not ready:
                self._timed_out = True
                return None
            chunk = os.read(fd, 1 << 16)
            if not chunk:
                return None
            self._buffer += chunk
        line, _, self._buffer = self._buffer.partition(b"\n")
        return line

    def run(self, case: Case, settle_ms: int = 0) -> dict[str, Any]:
        """The oracle's result for ``case`` (see ``oracle_worker.run_case``).

        With ``settle_ms``, each ``tickOnce`` gives timers that long to signal a wake-up
        (``oracle_worker.tick_once_settled``).
        """
        request = case.to_json()
        request["settle_ms"] = settle_ms
        line = (json.dumps(request) + "\n").encode()
        proc = self._start()
        assert proc.stdin is not None
        try:
            proc.stdin.write(line)
            proc.stdin.flush()
        except BrokenPipeError:
            self._kill()
            proc = self._start()
            assert proc.stdin is not None
            proc.stdin.write(line)
            proc.stdin.flush()
        line = self._read_line()
        if line is None:
            with contextlib.suppress(subprocess.TimeoutExpired):  # no output: dying, or hung
                proc.wait(timeout=0 if self._timed_out else 5)
            hung = proc.poll() is None
            self._kill()
            return {"load_error": None, "steps": [], "crashed": not hung, "hung": hung}
        result: dict[str, Any] = json.loads(line)
        done = self._read_line()
        if done is None:  # the tree's destructor aborted the worker
            result["destructor_abort"] = True
            self._kill()
        return result
