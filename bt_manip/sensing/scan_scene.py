"""The world cut at a laser's scan plane, kept up to date as bodies move, come and go.

:class:`ScanScene` holds the 2D sections (:mod:`bt_manip.sensing.sections`) of every body of a
:class:`~bt_manip.sim.world.World` at one height:

- walls and furniture (static) are cut once per height, their edges kept as one array;
- movable objects (a held one included) and robots are *pieces* (one per link with collision
  shapes) whose section is kept in the piece's planar frame (its centre of mass at (x, y),
  turned by its heading) together with what it depends on: the piece's height, roll and pitch
  and the plane's height. A piece that only moved in the plane (a robot driving on the floor)
  keeps its section, moved rigidly; one that tilted, rose or sank (an arm link, an object
  lifted) is cut again. A piece that stays farther from the plane than its shapes reach is
  not cut at all.
- bodies added while the world runs (a crate dropped by a fault, a model spawned) are found
  at the next :meth:`ScanScene.section`, bodies removed are dropped.

The ground plane is never part of a section.
"""

from __future__ import annotations

import math
from collections.abc import Collection
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pybullet as pb

from bt_manip.geometry import rotation_matrix
from bt_manip.sensing.raycast import polygon_segments
from bt_manip.sensing.sections import Section, planar_split, shape_section
from bt_manip.sim import pybullet_queries as pbq

if TYPE_CHECKING:
    from bt_manip.sim.world import World

__all__ = ["MOVING_KINDS", "ScanScene", "Segments"]

MOVING_KINDS = ("object", "robot")
"""Kinds of the World's bodies that may move (each link is cut again when it tilts or
changes height); walls and furniture are cut once."""
HEIGHT_TOLERANCE = 1e-4
"""m: the static bodies are cut again when the plane's height moves by more than this."""
POSE_TOLERANCE = 1e-7
"""A piece is cut again when its height (m), or an entry of its rotation with the heading
taken out, changes by more than this, or the plane's height does."""


@dataclass(frozen=True)
class Segments:
    """A scene's section as the ray caster takes it: edges (k, 4: ax, ay, bx, by) of
    counter-clockwise polygons and circles (m, 3: cx, cy, r), world frame."""

    segments: np.ndarray
    circles: np.ndarray


@dataclass
class _Shape:
    geometry: int
    dimensions: tuple[float, ...]
    position: np.ndarray
    """The shape's frame in its link's centre-of-mass frame (the link's frame for a mesh,
    whose vertices come in it)."""
    rotation: np.ndarray
    vertices: np.ndarray | None


@dataclass
class _Piece:
    """One link with collision shapes of a body that moves."""

    body: int
    link: int
    shapes: list[_Shape]
    reach: float
    """Farthest any of its shapes reaches from the link's centre of mass (m)."""
    key: np.ndarray | None = None
    section: Section = field(default_factory=Section)


class ScanScene:
    """The bodies of ``world`` cut by horizontal planes (see the module docstring)."""

    def __init__(self, world: World) -> None:
        self.world = world
        self.client = world.client
        self._static: dict[int, list[_Shape]] = {}
        self._static_height = math.nan
        self._static_cut: Segments | None = None
        self._pieces: dict[int, list[_Piece]] = {}
        self._bodies: tuple[int, ...] = ()
        self.cuts = 0
        """Pieces cut so far (moving ones), for checks that sections are kept."""

    # -- bodies ---------------------------------------------------------------------------
    def _sync_bodies(self) -> None:
        """Take in bodies added to the world and drop bodies removed since the last call."""
        infos = [i for i in self.world.infos.values() if i.kind != "ground"]
        ids = tuple(i.body_id for i in infos)
        if ids == self._bodies:
            return
        self._bodies = ids
        present = set(ids)
        for body in [b for b in self._static if b not in present]:
            del self._static[body]
            self._static_cut = None
        for body in [b for b in self._pieces if b not in present]:
            del self._pieces[body]
        for info in infos:
            body = info.body_id
            if info.kind in MOVING_KINDS:
                if body not in self._pieces:
                    self._pieces[body] = self._body_pieces(body)
            elif body not in self._static:
                self._static[body] = [s for link in self._links(body)
                                      for s in self._shapes(body, link, world_frame=True)]
                self._static_cut = None

    def _links(self, body: int) -> list[int]:
        return list(range(-1, pbq.joint_count(self.client, body)))

    def _shapes(self, body: int, link: int, world_frame: bool = False) -> list[_Shape]:
        """The collision shapes of a link, in its centre-of-mass frame (``world_frame``: in
        the world frame, where the link is now)."""
        out = []
        for index, shape in enumerate(pbq.collision_shapes(self.client, body, link)):
            geom = shape.geometry_type
            if geom == pb.GEOM_PLANE:
                continue
            vertices = None
            if geom == pb.GEOM_MESH:
                vertices = pbq.mesh_vertices(self.client, body, link, index)
                if not len(vertices):
                    continue
                position, rotation = np.zeros(3), np.eye(3)
            else:
                position = np.asarray(shape.local_position, dtype=float)
                rotation = rotation_matrix(shape.local_orientation)
            out.append(_Shape(geom, tuple(shape.dimensions), position, rotation, vertices))
        if out and world_frame:
            com_p, com_q = pbq.com_pose(self.client, body, link)
            p, r = np.asarray(com_p, dtype=float), rotation_matrix(com_q)
            for s in out:
                s.position, s.rotation = p + r @ s.position, r @ s.rotation
        return out

    def _body_pieces(self, body: int) -> list[_Piece]:
        pieces = []
        for link in self._links(body):
            shapes = self._shapes(body, link)
            if shapes:
                pieces.append(_Piece(body, link, shapes, max(_reach(s) for s in shapes)))
        return pieces

    # -- sections -------------------------------------------------------------------------
    def section(self, height: float) -> Segments:
        """Everything the plane ``z = height`` cuts, world frame, as of the bodies' poses now."""
        self._sync_bodies()
        static = self._static_section(height)
        moving = [self._moving_section(body, pieces, height)
                  for body, pieces in self._pieces.items()]
        parts = [static] + [m for m in moving if m is not None]
        if len(parts) == 1:
            return static
        return Segments(np.concatenate([p.segments for p in parts]),
                        np.concatenate([p.circles for p in parts]))

    def bodies_section(self, height: float, bodies: Collection[int]) -> Segments:
        """What the plane ``z = height`` cuts of the moving ``bodies`` alone (a robot and what
        it holds: the model a laser's self filter compares returns with), world frame."""
        self._sync_bodies()
        parts = [m for body in bodies if body in self._pieces
                 if (m := self._moving_section(body, self._pieces[body], height)) is not None]
        if not parts:
            return Segments(np.zeros((0, 4)), np.zeros((0, 3)))
        return Segments(np.concatenate([p.segments for p in parts]),
                        np.concatenate([p.circles for p in parts]))

    def _static_section(self, height: float) -> Segments:
        if self._static_cut is None or abs(height - self._static_height) > HEIGHT_TOLERANCE:
            cut = Section.join([
                shape_section(s.geometry, s.dimensions, s.position, s.rotation, height, s.vertices)
                for shapes in self._static.values() for s in shapes
            ])
            self._static_cut = Segments(polygon_segments(cut.polygons), cut.circles)
            self._static_height = height
        return self._static_cut

    def _moving_section(self, body: int, pieces: list[_Piece], height: float) -> Segments | None:
        links = [p.link for p in pieces if p.link >= 0]
        states = dict(zip(links, pbq.link_states(self.client, body, links), strict=True)) \
            if links else {}
        parts = []
        for piece in pieces:
            if piece.link < 0:
                pos, quat = pb.getBasePositionAndOrientation(body, physicsClientId=self.client)
            else:
                state = states[piece.link]
                pos, quat = state.com_position, state.com_orientation
            if abs(pos[2] - height) > piece.reach:
                continue
            x, y, yaw, local_p, local_r = planar_split(np.asarray(pos, dtype=float),
                                                       rotation_matrix(quat))
            key = np.concatenate([[local_p[2], height], local_r.ravel()])
            if piece.key is None or np.max(np.abs(piece.key - key)) > POSE_TOLERANCE:
                piece.section = Section.join([
                    shape_section(s.geometry, s.dimensions, local_p + local_r @ s.position,
                                  local_r @ s.rotation, height, s.vertices)
                    for s in piece.shapes
                ])
                piece.key = key
                self.cuts += 1
            if piece.section.polygons or len(piece.section.circles):
                parts.append(piece.section.moved(x, y, yaw))
        if not parts:
            return None
        cut = Section.join(parts)
        return Segments(polygon_segments(cut.polygons), cut.circles)


def _reach(shape: _Shape) -> float:
    """How far the shape reaches from its link's centre of mass, at most (m)."""
    centre = float(np.linalg.norm(shape.position))
    dims = shape.dimensions
    if shape.vertices is not None:
        return float(np.max(np.linalg.norm(shape.vertices, axis=1)))
    if shape.geometry == pb.GEOM_BOX:
        return centre + 0.5 * math.sqrt(dims[0] ** 2 + dims[1] ** 2 + dims[2] ** 2)
    if shape.geometry == pb.GEOM_SPHERE:
        return centre + dims[0]
    return centre + dims[0] / 2.0 + dims[1]  # cylinder and capsule: half length + radius
