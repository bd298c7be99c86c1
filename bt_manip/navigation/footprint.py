"""The robot's outline on the ground, growing with what it carries.

A :class:`PlanarFootprint` is a set of outlines (discs and convex polygons) in the robot's base
frame: x forward, y to the left, origin at the base's root link. The planner uses its
:attr:`~PlanarFootprint.half_width` (the robot drives along its path, so this is the clearance
it needs on each side) and the controller its :attr:`~PlanarFootprint.circumradius` (what it
sweeps when turning in place).

While an object is attached, :meth:`PlanarFootprint.with_body` adds that object's outline, as it
sits relative to the robot at that moment: a 1.2 m panel held across the robot makes the
footprint 1.2 m wide, and narrow doorways close for the planner.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from bt_manip.navigation.shapes import Disc, Outline, Polygon, ZBand, body_outlines, planar_frame


@dataclass(frozen=True)
class PlanarFootprint:
    """Outlines in the robot base frame, and a label saying what they cover."""

    outlines: tuple[Outline, ...]
    label: str = "robot"

    @classmethod
    def rectangle(
        cls, length: float, width: float, x_offset: float = 0.0, label: str = "robot"
    ) -> PlanarFootprint:
        hl, hw = length / 2.0, width / 2.0
        v = np.array(
            [
                [x_offset - hl, -hw],
                [x_offset + hl, -hw],
                [x_offset + hl, hw],
                [x_offset - hl, hw],
            ]
        )
        return cls((Polygon(v),), label)

    @classmethod
    def circle(cls, radius: float, label: str = "robot") -> PlanarFootprint:
        return cls((Disc(0.0, 0.0, radius),), label)

    @classmethod
    def from_description(cls, footprint: Any, label: str = "robot") -> PlanarFootprint:
        """From a robot descriptor's ``footprint`` (rectangle or circle)."""
        if getattr(footprint, "radius", 0.0) > 0.0:
            return cls.circle(footprint.radius, label)
        return cls.rectangle(footprint.length, footprint.width, footprint.x_offset, label)

    @classmethod
    def of_robot(cls, robot: Any, band: ZBand | None = None) -> PlanarFootprint:
        """The descriptor's footprint joined with the robot's own collision shapes.

        ``band`` (m above the base frame) defaults to everything from 2 cm up. The shapes are
        taken where they are now (arm posture included), in the base frame.
        """
        desc = robot.description
        base = cls.from_description(desc.footprint, desc.name)
        frame = planar_frame(*robot.base_pose2d())
        shapes = body_outlines(robot.client, robot.body, band or (0.02, 10.0), reference=frame)
        return cls(base.outlines + tuple(shapes), desc.name)

    def with_body(
        self, robot: Any, body: int, name: str = "object", band: ZBand | None = None
    ) -> PlanarFootprint:
        """This footprint plus ``body``'s outline where it sits relative to ``robot`` now."""
        frame = planar_frame(*robot.base_pose2d())
        client = robot.client
        shapes = body_outlines(client, body, band or (0.02, 10.0), reference=frame)
        return PlanarFootprint(self.outlines + tuple(shapes), f"{self.label} + {name}")

    # -- measures ----------------------------------------------------------------------------------
    def points(self) -> np.ndarray:
        """Points covering every outline (discs by a circumscribed polygon)."""
        return np.concatenate([o.points(48) for o in self.outlines])

    @property
    def half_width(self) -> float:
        """Largest distance of the footprint from the robot's x axis (m)."""
        return max(
            abs(o.cy) + o.radius if isinstance(o, Disc) else float(np.abs(o.vertices[:, 1]).max())
            for o in self.outlines
        )

    @property
    def circumradius(self) -> float:
        """Largest distance of the footprint from the base origin (m): swept when turning."""
        return max(
            math.hypot(o.cx, o.cy) + o.radius
            if isinstance(o, Disc)
            else float(np.hypot(o.vertices[:, 0], o.vertices[:, 1]).max())
            for o in self.outlines
        )

    @property
    def front(self) -> float:
        """How far the footprint reaches ahead of the base origin (m)."""
        return float(self.points()[:, 0].max())

    @property
    def rear(self) -> float:
        """How far the footprint reaches behind the base origin (m, positive)."""
        return float(-self.points()[:, 0].min())

    def describe(self) -> str:
        return (
            f"{self.label}: half width {self.half_width:.2f} m, "
            f"turning radius {self.circumradius:.2f} m"
        )
