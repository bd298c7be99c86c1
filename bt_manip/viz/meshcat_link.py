"""A guarded connection to a meshcat server: start one or attach to one, never hang.

meshcat's own ``Visualizer`` waits forever for a server that is not there. :class:`MeshcatLink`
talks the same ZeroMQ protocol with time-outs: it either starts a server in a subprocess (the
``meshcat.servers.zmqserver`` module of the installed package, which picks free ports) or
attaches to ``zmq_url``; when the server does not answer within ``timeout`` it raises
:class:`ViewerUnavailable` and the caller goes on without a viewer.
"""

from __future__ import annotations

import contextlib
import subprocess
import threading
import warnings
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


class MeshcatLink:
    """Send meshcat commands (lowered dicts) to a meshcat server.

    Args:
        zmq_url: attach to the server listening there; None starts a private server.
        timeout: seconds to wait for any answer before giving up.
    """

    def __init__(self, zmq_url: str | None = None, timeout: float = DEFAULT_TIMEOUT) -> None:
        self.timeout = timeout
        self.server: subprocess.Popen[bytes] | None = None
        self._context = zmq.Context.instance()
        self._socket: Any = None
        if zmq_url is None:
            try:
                with warnings.catch_warnings():  # meshcat imports a deprecated pyzmq module
                    warnings.simplefilter("ignore", DeprecationWarning)
                    from meshcat.servers.zmqserver import start_zmq_server_as_subprocess

                self.server, zmq_url, _ = start_zmq_server_as_subprocess()
                _drain(self.server)
            except Exception as exc:  # the server could not start: no viewer
                raise ViewerUnavailable(f"could not start a meshcat server ({exc})") from None
        self.zmq_url: str = zmq_url
        self._connect()
        try:
            self.web_url = self._request(b"url").decode()
        except ViewerUnavailable:
            self.close()
            raise
        # meshcat reconnects after asking for the URL; do the same
        self._connect()

    def _connect(self) -> None:
        if self._socket is not None:
            self._socket.close(linger=0)
        # a DEALER talks to meshcat's REP socket like a REQ, but can have several requests in
        # flight: a batch of commands costs one round trip instead of one each
        sock = self._context.socket(zmq.DEALER)
        sock.setsockopt(zmq.LINGER, 0)
        sock.setsockopt(zmq.RCVTIMEO, int(self.timeout * 1000))
        sock.setsockopt(zmq.SNDTIMEO, int(self.timeout * 1000))
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
            with contextlib.suppress(Exception):
                self.server.kill()
                self.server.wait(timeout=5)
            self.server = None
