"""Walls, furniture and the ground as PyBullet's static rigid bodies.

A body made with ``createMultiBody`` is by default an articulated body (a multibody) even
when it has no links and no mass, and PyBullet's multibody world does work for every such body
at every step, moving or not: about 0.17 us per body per step, 5 us per step for the 28 walls
and pieces of furniture of Scenario A's house, which is 4 % of the step. The same body made
with maximal coordinates is a static rigid body, which costs next to nothing; it has the same
collision shapes, the same place, the same id, and touches what touches it just the same.

PyBullet does not answer ``getCollisionShapeData`` for such a body. :func:`make_static` makes
one and registers what that query would have said of the multibody
(:func:`bt_manip.sim.pybullet_queries.register_collision_shapes`), asked once per process and
shape of a hidden client (:func:`collision_data`): the same numbers to the last bit, the margin
PyBullet adds and takes away included.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import pybullet as pb

from bt_manip.cache import Memo
from bt_manip.sim import pybullet_queries as pbq

_DATA: Memo[tuple[pbq.ShapeData, ...]] = Memo(1024)
"""The collision shape data of each shape asked for, by its creation arguments."""

_PROBE_RESET_EVERY = 256
"""Shapes made in the hidden client before it is reset (PyBullet keeps every shape made)."""


@dataclass
class _Probe:
    """The hidden client that :func:`collision_data` asks (connected on first use)."""

    client: int = -1
    made: int = 0

    def connected(self) -> int:
        """The client, connected (again if needed) and reset every so many shapes."""
        if self.client >= 0 and pb.isConnected(self.client):
            if self.made >= _PROBE_RESET_EVERY:
                pb.resetSimulation(physicsClientId=self.client)
                self.made = 0
            return self.client
        self.client, self.made = int(pb.connect(pb.DIRECT)), 0
        return self.client


_PROBE = _Probe()


def _key(array: bool, shape: dict[str, Any]) -> str:
    return repr((array, sorted(shape.items())))


def collision_data(array: bool, shape: dict[str, Any]) -> tuple[pbq.ShapeData, ...]:
    """What ``getCollisionShapeData`` says of a body without links whose base has the collision
    shape ``createCollisionShapeArray(**shape)`` (``array``) or ``createCollisionShape(**shape)``
    makes (``body`` set to -1, ``link`` to -1)."""
    key = _key(array, shape)
    known = _DATA.get(key)
    if known is not None:
        return known
    c = _PROBE.connected()
    make = pb.createCollisionShapeArray if array else pb.createCollisionShape
    col = make(**shape, physicsClientId=c)
    body = pb.createMultiBody(0, col, -1, [0.0, 0.0, 0.0], physicsClientId=c)
    _PROBE.made += 1
    try:
        # every shape is the base's (PyBullet fills the body and link of a compound's later
        # children with whatever its buffer held)
        data = tuple(s._replace(body=-1, link=-1) for s in pbq.collision_shapes(c, body, -1))
    finally:
        pb.removeBody(body, physicsClientId=c)
    _DATA.put(key, data)
    return data


def make_static(
    client: int,
    array: bool,
    shape: dict[str, Any],
    visual: int,
    position: list[float],
    orientation: list[float] | tuple[float, ...] = (0.0, 0.0, 0.0, 1.0),
) -> int:
    """A static rigid body with the collision shape ``shape`` (see :func:`collision_data`) and
    the visual shape ``visual`` (-1: PyBullet's own, drawn from the collision shape), at
    ``position``/``orientation``; its collision shape data registered for
    :func:`~bt_manip.sim.pybullet_queries.collision_shapes`."""
    make = pb.createCollisionShapeArray if array else pb.createCollisionShape
    col = make(**shape, physicsClientId=client)
    body = int(pb.createMultiBody(
        0, col, visual, position, list(orientation), useMaximalCoordinates=True,
        physicsClientId=client,
    ))
    pbq.register_collision_shapes(
        client, body, [s._replace(body=body) for s in collision_data(array, shape)]
    )
    return body
