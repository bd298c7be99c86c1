"""Planar poses ``(x, y, yaw)`` as rigid motions: composed, inverted, headings wrapped.

``map -> odom`` of a localising robot, the believed pose (``map -> odom * odometry``) and the
passage of a map-frame target into the world (``true_base * inverse(believed_base) * target``)
are all written with these.
"""

from __future__ import annotations

import math

Pose = tuple[float, float, float]
"""A planar pose: x, y (m), yaw (rad)."""


def wrap(a: float) -> float:
    """The angle ``a`` (rad) brought within -pi..pi."""
    return math.atan2(math.sin(a), math.cos(a))


def compose(a: Pose, b: Pose) -> Pose:
    """The planar pose ``a * b``: ``b`` expressed in ``a``'s frame, in ``a``'s parent."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap(a[2] + b[2]))


def inverse(a: Pose) -> Pose:
    """The planar pose ``a`` inverted: ``compose(a, inverse(a))`` is the identity."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (-c * a[0] - s * a[1], s * a[0] - c * a[1], wrap(-a[2]))
