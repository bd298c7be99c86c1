"""A minimal Groot2 client (pyzmq) for the tests: requests, replies, the PUB socket."""

from __future__ import annotations

import socket
import struct
from typing import Any

import zmq


def free_port_pair() -> int:
    """A port P such that P and P+1 were free a moment ago (for BT.CPP's publisher)."""
    for _ in range(100):
        with socket.socket() as a:
            a.bind(("127.0.0.1", 0))
            port = a.getsockname()[1]
            with socket.socket() as b:
                try:
                    b.bind(("127.0.0.1", port + 1))
                except OSError:
                    continue
                return port
    raise RuntimeError("no free pair of ports")


class GrootClient:
    """Sends Groot2 requests to ``port`` and subscribes to ``port + 1``."""

    def __init__(self, port: int, timeout_ms: int = 5000) -> None:
        self.context = zmq.Context()
        self.port = port
        self.timeout_ms = timeout_ms
        self.request_id = 0
        self._connect()
        self.sub = self.context.socket(zmq.SUB)
        self.sub.setsockopt(zmq.LINGER, 0)
        self.sub.setsockopt(zmq.RCVTIMEO, timeout_ms)
        self.sub.setsockopt(zmq.SUBSCRIBE, b"")
        self.sub.connect(f"tcp://127.0.0.1:{port + 1}")

    def _connect(self) -> None:
        self.req = self.context.socket(zmq.REQ)
        self.req.setsockopt(zmq.LINGER, 0)
        self.req.setsockopt(zmq.RCVTIMEO, self.timeout_ms)
        self.req.connect(f"tcp://127.0.0.1:{self.port}")

    def raw(self, frames: list[bytes]) -> list[bytes]:
        self.req.send_multipart(frames)
        return self.req.recv_multipart()

    def request(self, kind: str, *parts: Any, protocol: int = 2) -> list[bytes]:
        self.request_id += 1
        header = struct.pack("<BBI", protocol, ord(kind), self.request_id)
        frames = [header] + [p if isinstance(p, bytes) else str(p).encode() for p in parts]
        return self.raw(frames)

    def close(self) -> None:
        self.req.close()
        self.sub.close()
        self.context.term()


def sync_subscription(client: GrootClient, publisher: Any, limit_s: float = 30.0) -> None:
    """Wait until ``client``'s SUB socket gets what the in-process ``publisher`` publishes.

    ZMQ drops what a PUB socket sends before a subscriber's connection is made; Groot2
    subscribes long before any breakpoint, a test that ticks at once must wait for it. Call
    before the tree's thread starts (the PUB socket is then free to use from here).
    """
    import time

    deadline = time.monotonic() + limit_s
    client.sub.setsockopt(zmq.RCVTIMEO, 50)
    try:
        while time.monotonic() < deadline:
            publisher._pub.send(b"sync")
            try:
                if client.sub.recv() == b"sync":
                    break
            except zmq.Again:
                continue
        else:
            raise RuntimeError("the subscription never connected")
        while True:
            try:
                client.sub.recv()
            except zmq.Again:
                break
    finally:
        client.sub.setsockopt(zmq.RCVTIMEO, client.timeout_ms)
