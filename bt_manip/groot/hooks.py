"""Groot2 hooks: breakpoints (mode 0) and replace-hooks (mode 1), as BT.CPP's publisher has them.

A hook sits before a node's tick (position 0; BT.CPP inserts no other). When the node is about
to tick (it is not finished and no pre-condition decided its status), an enabled hook
announces itself on the PUB socket; a breakpoint then blocks the tree's thread until Groot2
unlocks it (or the hook is disabled or removed). Finally a SUCCESS or FAILURE desired status
replaces the node's tick, any other status lets the node tick as usual.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bt_manip.bt.status import NodeStatus

BREAKPOINT = 0
REPLACE = 1
PRE = 0
POST = 1


class HookError(ValueError):
    """A hook request that cannot be understood."""


@dataclass
class Hook:
    """One hook on the node with UID ``uid``."""

    uid: int
    enabled: bool = True
    mode: int = BREAKPOINT
    once: bool = False
    desired_status: NodeStatus = NodeStatus.IDLE
    position: int = PRE
    remove_when_done: bool = False
    ready: bool = False

    def update(self, data: dict[str, Any]) -> None:
        """Take the fields of a HOOK_INSERT JSON object."""
        self.enabled = _field(data, "enabled", bool)
        self.uid = _field(data, "uid", int)
        self.mode = _field(data, "mode", int)
        if self.mode not in (BREAKPOINT, REPLACE):
            raise HookError(f"hook mode must be 0 (breakpoint) or 1 (replace), got {self.mode}")
        self.once = _field(data, "once", bool)
        self.desired_status = parse_status(_field(data, "desired_status", str))
        self.position = _field(data, "position", int)
        self.remove_when_done = self.remove_when_done or self.once

    def to_json(self) -> dict[str, Any]:
        return {
            "desired_status": self.desired_status.value,
            "enabled": self.enabled,
            "mode": self.mode,
            "once": self.once,
            "position": self.position,
            "uid": self.uid,
        }


def parse_status(text: str) -> NodeStatus:
    try:
        return NodeStatus.parse(text)
    except ValueError as e:
        raise HookError(f"desired_status: {e}") from None


def _field(data: dict[str, Any], key: str, kind: type) -> Any:
    if not isinstance(data, dict):
        raise HookError("a hook must be a JSON object")
    if key not in data:
        raise HookError(f"hook without '{key}'")
    value = data[key]
    if (kind is int and isinstance(value, bool)) or not isinstance(value, kind):
        raise HookError(f"hook field '{key}' must be {kind.__name__}, got {value!r}")
    return value


def unlock_status(text: Any) -> NodeStatus:
    """The status a BREAKPOINT_UNLOCK asks for: SUCCESS, FAILURE, anything else SKIPPED."""
    if text == "SUCCESS":
        return NodeStatus.SUCCESS
    if text == "FAILURE":
        return NodeStatus.FAILURE
    return NodeStatus.SKIPPED
