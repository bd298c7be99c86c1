"""MeshcatLink against a stand-in meshcat server (a ZeroMQ REP socket in a thread)."""

from __future__ import annotations

import socket
import threading
import time

import numpy as np
import pytest
import zmq

from bt_manip.viz.meshcat_link import MeshcatLink, ViewerUnavailable


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class StandInServer:
    """Answers every request like meshcat's server does (the web URL for ``url``, ``ok`` else)
    and remembers the command types it got."""

    def __init__(self, url: str) -> None:
        self.url = url
        self.got: list[bytes] = []
        self._stop = threading.Event()
        self._ready = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()
        assert self._ready.wait(15)

    def _serve(self) -> None:
        sock = zmq.Context.instance().socket(zmq.REP)
        sock.setsockopt(zmq.LINGER, 0)
        deadline = time.monotonic() + 10
        while True:  # the port a server before this one had is freed a moment after it closed
            try:
                sock.bind(self.url)
                break
            except zmq.ZMQError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.02)
        self._ready.set()
        try:
            while not self._stop.is_set():
                if not sock.poll(20):
                    continue
                frames = sock.recv_multipart()
                self.got.append(frames[0])
                sock.send(b"http://127.0.0.1:7000/static/" if frames[0] == b"url" else b"ok")
        finally:
            sock.close(linger=0)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(5)


def test_a_link_never_talks_to_a_new_server_on_a_lost_servers_port() -> None:
    url = f"tcp://127.0.0.1:{_free_port()}"
    first = StandInServer(url)
    link = MeshcatLink(zmq_url=url, timeout=0.3)
    try:
        link.set_transform("/a", list(np.eye(4).ravel()))
        assert first.got == [b"url", b"set_transform"]
        first.stop()
        # another server takes the port (as another run's viewer can on a busy machine) and
        # has had ample time to be found by a link that reconnects
        second = StandInServer(url)
        time.sleep(0.5)
        with pytest.raises(ViewerUnavailable, match="no answer from the meshcat server"):
            link.set_transform("/a", list(np.eye(4).ravel()))
        second.stop()
        assert second.got == []
    finally:
        link.close()
