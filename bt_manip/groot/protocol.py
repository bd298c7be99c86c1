"""The Groot2 wire format (protocol 2): headers, status codes and transitions.

A request's first frame is 6 bytes, little-endian: ``uint8 protocol`` (2), ``uint8 type`` (an
ASCII letter, :class:`RequestType`), ``uint32 request_id``. A reply's first frame echoes that
header (protocol forced to 2) followed by the publisher's 16-byte tree UUID; an error reply is
the two frames ``["error", message]`` and no header.
"""

from __future__ import annotations

import enum
import os
import struct
from collections.abc import Iterable

from bt_manip.bt.status import STATUS_CODES, NodeStatus

PROTOCOL_ID = 2
REQUEST_HEADER_SIZE = 6
_HEADER = struct.Struct("<BBI")
_TRANSITION_TAIL = struct.Struct("<HB")

IDLE_OFFSET = 10
"""A node back to IDLE shows in STATUS as 10 + the status it had before."""


class RequestType(enum.IntEnum):
    """Request types, by their ASCII letter."""

    FULLTREE = ord("T")
    STATUS = ord("S")
    BLACKBOARD = ord("B")
    HOOK_INSERT = ord("I")
    HOOK_REMOVE = ord("R")
    BREAKPOINT_REACHED = ord("N")
    BREAKPOINT_UNLOCK = ord("U")
    HOOKS_DUMP = ord("D")
    REMOVE_ALL_HOOKS = ord("A")
    DISABLE_ALL_HOOKS = ord("X")
    TOGGLE_RECORDING = ord("r")
    GET_TRANSITIONS = ord("t")


def request_header(kind: int, request_id: int = 0, protocol: int = PROTOCOL_ID) -> bytes:
    """The 6-byte request header."""
    return _HEADER.pack(protocol, kind, request_id)


def parse_request_header(frame: bytes) -> tuple[int, int, int] | None:
    """``(protocol, type, request_id)``, or None when the frame is not 6 bytes long."""
    if len(frame) != REQUEST_HEADER_SIZE:
        return None
    return _HEADER.unpack(frame)


def reply_header(kind: int, request_id: int, tree_uuid: bytes) -> bytes:
    """The 22-byte reply header: the request header (protocol 2) then the tree UUID."""
    return _HEADER.pack(PROTOCOL_ID, kind, request_id) + tree_uuid


def random_tree_uuid() -> bytes:
    """16 random bytes shaped as a version-4 UUID (one per publisher)."""
    raw = bytearray(os.urandom(16))
    raw[6] = (raw[6] & 0x4F) | 0x40
    raw[8] = (raw[8] & 0xBF) | 0x80
    return bytes(raw)


def status_code(previous: NodeStatus, new: NodeStatus) -> int:
    """The STATUS byte of a node that went from ``previous`` to ``new``."""
    if new is NodeStatus.IDLE:
        return IDLE_OFFSET + STATUS_CODES[previous]
    return STATUS_CODES[new]


def encode_transitions(transitions: Iterable[tuple[int, int, int]]) -> bytes:
    """9 bytes per ``(timestamp_us, uid, status)``: 6-byte timestamp, uint16 uid, uint8 status."""
    out = bytearray()
    for stamp, uid, status in transitions:
        out += (stamp & 0xFFFF_FFFF_FFFF).to_bytes(6, "little")
        out += _TRANSITION_TAIL.pack(uid, status)
    return bytes(out)


def decode_transitions(data: bytes) -> list[tuple[int, int, int]]:
    """The inverse of :func:`encode_transitions`."""
    if len(data) % 9:
        raise ValueError(f"transition data of {len(data)} bytes is not a multiple of 9")
    out = []
    for offset in range(0, len(data), 9):
        stamp = int.from_bytes(data[offset:offset + 6], "little")
        uid, status = _TRANSITION_TAIL.unpack_from(data, offset + 6)
        out.append((stamp, uid, status))
    return out
