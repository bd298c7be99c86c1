"""``.btlog`` files (BehaviorTree.CPP's FileLogger2 format), which Groot2 replays.

Layout: the 18 ASCII bytes ``BTCPP4-FileLogger2``, ``uint8`` version 1, ``int32`` length of the
tree XML, the XML (as Groot2's FULLTREE: ``_uid`` and ``_fullpath`` on every node, then the
TreeNodesModel), ``int64`` start time (microseconds since the Unix epoch), then one 9-byte
transition per status change: 6-byte timestamp in microseconds since the start, ``uint16``
node UID, ``uint8`` new status (0 IDLE, 1 RUNNING, 2 SUCCESS, 3 FAILURE, 4 SKIPPED), all
little-endian. bt-manip's timestamps are the run's sim time.
"""

from __future__ import annotations

import struct
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, BinaryIO

from bt_manip.bt.status import STATUS_CODES, NodeStatus
from bt_manip.groot.layout import registered_classes, tree_xml
from bt_manip.groot.monitor import TreeMonitor
from bt_manip.groot.protocol import decode_transitions

if TYPE_CHECKING:
    from bt_manip.run.runner import Runner

MAGIC = b"BTCPP4-FileLogger2"
_TRANSITION = struct.Struct("<IHHB")  # 48-bit timestamp as 32 + 16 bits, uid, status
VERSION = 1


class BtlogWriter:
    """Writes the status changes seen by ``monitor`` to ``path`` until :meth:`close`.

    A run hook (:class:`~bt_manip.run.hooks.RunHook`): the changes come from the monitor, so
    there is nothing to do after a tick; the runner closes it when the run ends."""

    def __init__(self, path: str | Path, monitor: TreeMonitor, xml: str | None = None) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.monitor = monitor
        text = (xml if xml is not None
                else tree_xml(monitor.layout, registered_classes())).encode()
        self._file: BinaryIO | None = self.path.open("wb")
        self._file.write(MAGIC + bytes([VERSION]) + struct.pack("<i", len(text)) + text)
        self._file.write(struct.pack("<q", time.time_ns() // 1000))
        monitor.consumers.append(self._record)

    def _record(self, uid: int, previous: NodeStatus, new: NodeStatus, stamp: int) -> None:
        if self._file is not None:
            self._file.write(_TRANSITION.pack(stamp & 0xFFFF_FFFF, (stamp >> 32) & 0xFFFF, uid,
                                              STATUS_CODES[new]))

    def __call__(self, runner: Runner) -> None:
        """After a tick: nothing (the monitor has passed on every change already)."""

    def close(self) -> None:
        """Flush and close the file (further changes are not written). Idempotent."""
        if self._file is None:
            return
        with self.monitor.lock:
            if self._record in self.monitor.consumers:
                self.monitor.consumers.remove(self._record)
            self._file.close()
            self._file = None


@dataclass
class Btlog:
    """A .btlog read back."""

    xml: str
    start_us: int
    transitions: list[tuple[int, int, int]]
    """``(timestamp_us, uid, status)`` in file order."""


def read_btlog(path: str | Path) -> Btlog:
    """Read a FileLogger2 file; ValueError with the reason when it is not one."""
    data = Path(path).read_bytes()
    head = len(MAGIC) + 1 + 4
    if len(data) < head or not data.startswith(MAGIC):
        raise ValueError(f"{path}: not a BTCPP4-FileLogger2 file")
    (size,) = struct.unpack_from("<i", data, len(MAGIC) + 1)
    if size < 0 or head + size + 8 > len(data):
        raise ValueError(f"{path}: truncated header (XML of {size} bytes)")
    xml = data[head:head + size].decode()
    (start,) = struct.unpack_from("<q", data, head + size)
    body = data[head + size + 8:]
    body = body[:len(body) - len(body) % 9]
    return Btlog(xml, start, decode_transitions(body))
