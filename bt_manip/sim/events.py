"""What a running World announces: bodies added and removed, objects attached and let go.

Whatever shows or records a run (the live viewer, the replay recorder) subscribes to the
World's :class:`WorldEvents` instead of reading PyBullet's body list on its own::

    unsubscribe = world.events.subscribe(listener)   # listener(event) for each change

The World calls every listener synchronously, in the order they subscribed, right after the
change is done (so a listener may query the body it is told about). Events carry the sim time
at which they happened. Poses are not announced: they change every physics step, and a
listener samples them when it needs them.

A listener must not change the world; an exception it raises reaches the code that changed
the world (it is not swallowed).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class BodyAdded:
    """A body entered the world while it runs (``SpawnModel``, a ``block`` fault's crate).

    ``kind`` is ``object`` (movable) or ``furniture`` (static); ``spec`` is the body's
    :class:`~bt_manip.sim.world_spec.BodySpec` (its parts, colours, URDF and scale).
    """

    time: float
    name: str
    body_id: int
    kind: str
    spec: Any


@dataclass(frozen=True)
class BodyRemoved:
    """A body left the world (``DeleteModel``)."""

    time: float
    name: str
    body_id: int
    kind: str


@dataclass(frozen=True)
class Attached:
    """An object was fixed to a robot link (it moves with the gripper from now on)."""

    time: float
    object_name: str
    robot_name: str
    link_name: str


@dataclass(frozen=True)
class Detached:
    """An attached object was let go (or removed from the world while held)."""

    time: float
    object_name: str
    robot_name: str


WorldEvent = BodyAdded | BodyRemoved | Attached | Detached
WorldListener = Callable[[WorldEvent], None]


class WorldEvents:
    """The listeners of one World, and how the World reaches them."""

    def __init__(self) -> None:
        self._listeners: list[WorldListener] = []

    def subscribe(self, listener: WorldListener) -> Callable[[], None]:
        """Call ``listener(event)`` on every change from now on; returns the unsubscribe call."""
        self._listeners.append(listener)

        def unsubscribe() -> None:
            if listener in self._listeners:
                self._listeners.remove(listener)

        return unsubscribe

    def announce(self, event: WorldEvent) -> None:
        """Tell every listener, in subscription order."""
        for listener in list(self._listeners):
            listener(event)

    def __len__(self) -> int:
        return len(self._listeners)
