"""A guarded connection to a meshcat server: start one or attach to one, never hang.

meshcat's own ``Visualizer`` waits forever for a server that is not there. :class:`MeshcatLink`
talks the same ZeroMQ protocol with time-outs: it either starts a server in a subprocess
(:mod:`bt_manip.viz.meshcat_server`: meshcat's server listening on one address, which picks
free ports and exits with its run) or attaches to ``zmq_url``; when the server does not answer
within ``timeout`` it raises :class:`ViewerUnavailable` and the caller goes on without a
viewer. :meth:`MeshcatLink.close` stops a server it started (and waits for it to exit).
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import umsgpack
import zmq

DEFAULT_TIMEOUT = 3.0


class ViewerUnavailable(RuntimeError):
    """The meshcat server could not be started or did not answer."""


def _drain(process: subprocess.Popen[bytes]) -> None:
    """Read the server's output in the background so that its pipes never fill up."""

    def read(stream: Any) -> None:
        with contextlib.suppress(Exception):
            for _ in iter(stream.readline, b""):
                pass

    for stream in (process.stdout, process.stderr):
        if stream is not None:
            threading.Thread(target=read, args=(stream,), daemon=True).start()


STARTUP_PATIENCE = 10.0
"""Seconds a server started here may take to answer its first requests (the URL, the world's
first drawing with every mesh) on a busy machine; later requests wait ``timeout``."""
SERVER_START_TIMEOUT = 20.0
"""Seconds a new meshcat server may take to print its addresses (importing tornado, zmq)."""


def _start_server(host: str, timeout: float) -> tuple[subprocess.Popen[bytes], str]:
    """Start :mod:`bt_manip.viz.meshcat_server`; its process and ZeroMQ address."""
    env = dict(os.environ)
    package_root = str(Path(__file__).resolve().parents[2])
    env["PYTHONPATH"] = os.pathsep.join(
        p for p in (package_root, env.get("PYTHONPATH", "")) if p
    )
    try:
        process = subprocess.Popen(
            [sys.executable, "-u", "-m", "bt_manip.viz.meshcat_server", "--host", host],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, env=env,
            start_new_session=True,  # Ctrl-C reaches the run, which then stops the server
        )
    except OSError as exc:
        raise ViewerUnavailable(f"could not start a meshcat server ({exc})") from None
    lines: list[str] = []

    def read_two() -> None:
        assert process.stdout is not None
        for _ in range(2):
            lines.append(process.stdout.readline().decode(errors="replace").strip())

    reader = threading.Thread(target=read_two, daemon=True)
    reader.start()
    reader.join(max(timeout, SERVER_START_TIMEOUT))
    zmq_url = lines[0].partition("zmq_url=")[2] if lines else ""
    if not zmq_url or reader.is_alive():
        process.kill()
        _, err = process.communicate(timeout=5)
        last = err.decode(errors="replace").strip().splitlines()[-1:] or ["no output"]
        raise ViewerUnavailable(f"could not start a meshcat server on {host} ({last[0]})")
    _drain(process)
    return process, zmq_url


class MeshcatLink:
    """Send meshcat commands (lowered dicts) to a meshcat server.

    Args:
        zmq_url: attach to the server listening there; None starts a private server.
        timeout: seconds to wait for any answer before giving up.
        host: the address a server started here listens on.
    """

    def __init__(self, zmq_url: str | None = None, timeout: float = DEFAULT_TIMEOUT,
                 host: str = "127.0.0.1") -> None:
        self.timeout = timeout
        self.server: subprocess.Popen[bytes] | None = None
        self._context: zmq.Context[Any] = zmq.Context.instance()
        self._socket: Any = None
        if zmq_url is None:
            self.server, zmq_url = _start_server(host, timeout)
        self.zmq_url: str = zmq_url
        # a server started here has just said it listens: give it time to answer on a busy
        # machine; a server someone else runs gets ``timeout``
        first = max(timeout, STARTUP_PATIENCE) if self.server is not None else timeout
        self._connect(first)
        try:
            self.web_url = self._request(b"url").decode()
        except ViewerUnavailable:
            self.close()
            raise
        # meshcat reconnects after asking for the URL; do the same
        self._connect(first)

    def settle(self) -> None:
        """From now on wait ``timeout`` for each answer (after the first drawing, which a
        server started here gets :data:`STARTUP_PATIENCE` for)."""
        if self._socket is not None:
            self._connect(self.timeout)

    def _connect(self, timeout: float | None = None) -> None:
        timeout = self.timeout if timeout is None else timeout
        if self._socket is not None:
            self._socket.close(linger=0)
        # a DEALER talks to meshcat's REP socket like a REQ, but can have several requests in
        # flight: a batch of commands costs one round trip instead of one each
        sock = self._context.socket(zmq.DEALER)
        sock.setsockopt(zmq.LINGER, 0)
        sock.setsockopt(zmq.RCVTIMEO, int(timeout * 1000))
        sock.setsockopt(zmq.SNDTIMEO, int(timeout * 1000))
        # a server that went away took the scene with it: never reconnect (to whatever listens
        # on its port next, e.g. another run's server), so the next request fails and the run
        # goes on without the live view
        sock.setsockopt(zmq.RECONNECT_IVL, -1)
        try:
            sock.connect(self.zmq_url)
        except zmq.ZMQError as exc:
            sock.close(linger=0)
            raise ViewerUnavailable(f"bad meshcat address '{self.zmq_url}': {exc}") from None
        self._socket = sock

    def _request(self, *frames: bytes) -> bytes:
        return self._exchange([list(frames)])[0]

    def _exchange(self, requests: list[list[bytes]]) -> list[bytes]:
        """Send every request, then collect one answer per request (in order)."""
        if self._socket is None:
            raise ViewerUnavailable("the meshcat connection is closed")
        try:
            for frames in requests:
                self._socket.send_multipart([b"", *frames])
            answers = []
            for _ in requests:
                reply = self._socket.recv_multipart()
                answers.append(reply[-1])
            return answers
        except zmq.ZMQError:
            raise ViewerUnavailable(
                f"no answer from the meshcat server at {self.zmq_url} within {self.timeout:g} s"
            ) from None

    def send(self, command: dict[str, Any]) -> None:
        """Send one lowered command (``type``, ``path``, ...); raises ViewerUnavailable."""
        self.send_many([command])

    def send_many(self, commands: list[dict[str, Any]]) -> None:
        """Send several commands in one round trip; raises ViewerUnavailable."""
        if commands:
            self._exchange(
                [[c["type"].encode(), c["path"].encode(), umsgpack.packb(c)] for c in commands]
            )

    def set_object(self, path: str, obj: dict[str, Any]) -> None:
        self.send({"type": "set_object", "path": path, "object": obj})

    def set_transform(self, path: str, matrix: list[float]) -> None:
        self.send({"type": "set_transform", "path": path, "matrix": matrix})

    def set_property(self, path: str, prop: str, value: Any) -> None:
        self.send({"type": "set_property", "path": path, "property": prop, "value": value})

    def delete(self, path: str) -> None:
        self.send({"type": "delete", "path": path})

    def close(self) -> None:
        """Disconnect, and stop the server if this link started it."""
        if self._socket is not None:
            self._socket.close(linger=0)
            self._socket = None
        if self.server is not None:
            stop_process(self.server)
            self.server = None


def stop_process(process: subprocess.Popen[bytes], grace: float = 2.0) -> None:
    """Terminate a child process, kill it if it has not exited after ``grace`` s, reap it."""
    if process.poll() is None:
        with contextlib.suppress(ProcessLookupError):
            process.terminate()
        deadline = time.monotonic() + grace
        while process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
        if process.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                process.kill()
    with contextlib.suppress(subprocess.TimeoutExpired):
        process.wait(timeout=5)
