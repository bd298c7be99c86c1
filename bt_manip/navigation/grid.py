"""Occupancy grids rasterised from the collision geometry of a PyBullet world.

An :class:`OccupancyGrid` covers a rectangle of the ground plane with square cells of side
``resolution`` (default 0.05 m). Cell ``(row, col)`` spans
``x in [x0 + col * res, x0 + (col + 1) * res)`` and ``y in [y0 + row * res, y0 + (row + 1) * res)``
where ``(x0, y0)`` is the grid's ``origin``: rows grow with y, columns with x.

:func:`rasterise` marks every cell whose square overlaps (with positive area) the outline of a
collision shape inside the height band the robot sweeps (see :mod:`bt_manip.navigation.shapes`).
Cells only touched along an edge or corner stay free, so a wall face lying on a cell border
does not spill into the next cell.

:meth:`OccupancyGrid.save_png` writes the grid as an image for a person to look at (north up,
occupied black); :func:`save_cost_png` does the same for a cost grid.
"""

from __future__ import annotations

import math
import struct
import threading
import zlib
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bt_manip.navigation.shapes import Disc, Outline, Polygon, ZBand, body_outlines
from bt_manip.sim import pybullet_queries as pbq

DEFAULT_RESOLUTION = 0.05
"""Cell side (m)."""

DEFAULT_BAND: ZBand = (0.02, 2.0)
"""Height band (m) looked at when none is given: from just above the floor to 2 m."""

MAX_CELLS = 25_000_000
"""Largest grid built (cells): at 0.05 m, a world of 250 m x 250 m."""

BLOCK_CELLS = 1 << 18
"""Cells tested at a time when a shape is drawn (bounds the temporaries of a large shape)."""

_EPS = 1e-9


class GridTooLarge(ValueError):
    """The grid asked for has more than :data:`MAX_CELLS` cells; the message says why."""


@dataclass
class OccupancyGrid:
    """Occupied cells of a rectangle of the ground plane (row = y, column = x)."""

    origin: tuple[float, float]
    resolution: float
    occupied: np.ndarray  # bool (rows, cols)
    band: ZBand = DEFAULT_BAND
    sources: dict[int, np.ndarray] = field(default_factory=dict, repr=False)
    """Per body id, the flat indices of the cells it occupies (for layers that move)."""

    @property
    def shape(self) -> tuple[int, int]:
        return self.occupied.shape  # type: ignore[return-value]

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the covered rectangle."""
        rows, cols = self.shape
        x0, y0 = self.origin
        return x0, y0, x0 + cols * self.resolution, y0 + rows * self.resolution

    @classmethod
    def empty(
        cls,
        extent: tuple[float, float, float, float],
        resolution: float = DEFAULT_RESOLUTION,
        band: ZBand = DEFAULT_BAND,
    ) -> OccupancyGrid:
        """A free grid covering ``(xmin, ymin, xmax, ymax)`` (rounded out to whole cells).

        Raises :class:`GridTooLarge` beyond :data:`MAX_CELLS` cells.
        """
        xmin, ymin, xmax, ymax = extent
        cols = max(1, math.ceil((xmax - xmin) / resolution - 1e-9))
        rows = max(1, math.ceil((ymax - ymin) / resolution - 1e-9))
        if rows * cols > MAX_CELLS:
            raise GridTooLarge(
                f"the occupancy grid would have {rows * cols:,} cells ({cols:,} x {rows:,}): the "
                f"world spans x {xmin:.2f}..{xmax:.2f} m, y {ymin:.2f}..{ymax:.2f} m (obstacles "
                f"plus margin) at a resolution of {resolution:g} m, and bt-manip allows at most "
                f"{MAX_CELLS:,} cells; make the world smaller")
        return cls(
            (float(xmin), float(ymin)), float(resolution), np.zeros((rows, cols), bool), band
        )

    def copy(self) -> OccupancyGrid:
        return OccupancyGrid(
            self.origin,
            self.resolution,
            self.occupied.copy(),
            self.band,
            {k: v.copy() for k, v in self.sources.items()},
        )

    # -- coordinates ---------------------------------------------------------------------------
    def world_to_cell(self, x: float, y: float) -> tuple[int, int]:
        """The (row, col) of the cell containing world point (x, y) (may be outside the grid)."""
        return (
            math.floor((y - self.origin[1]) / self.resolution),
            math.floor((x - self.origin[0]) / self.resolution),
        )

    def cell_to_world(self, row: float, col: float) -> tuple[float, float]:
        """World (x, y) of a cell's centre."""
        return (
            self.origin[0] + (col + 0.5) * self.resolution,
            self.origin[1] + (row + 0.5) * self.resolution,
        )

    def cells_to_world(self, cells: np.ndarray) -> np.ndarray:
        """World (x, y) of the centres of ``cells`` (n, 2) as an (n, 2) float array."""
        c = np.asarray(cells, dtype=float)
        return np.column_stack(
            [
                self.origin[0] + (c[:, 1] + 0.5) * self.resolution,
                self.origin[1] + (c[:, 0] + 0.5) * self.resolution,
            ]
        )

    def inside(self, cell: tuple[int, int]) -> bool:
        rows, cols = self.shape
        return 0 <= cell[0] < rows and 0 <= cell[1] < cols

    # -- drawing ---------------------------------------------------------------------------------
    def _hit_blocks(self, outline: Outline) -> Iterator[tuple[int, int, np.ndarray]]:
        """``(first row, first column, hit)`` per block of rows of the outline's bounding box:
        ``hit`` (read-only) marks the cells whose squares overlap ``outline`` with positive
        area. Blocks hold at most :data:`BLOCK_CELLS` cells, so a shape as large as the grid
        needs no temporaries the size of the grid.

        The blocks depend only on the outline's numbers and the grid's origin, resolution and
        shape, so those of small outlines are remembered for the process (:class:`_HitMemo`):
        the walls and furniture of a world are drawn again in every episode and every height
        band, mostly with the very same outlines."""
        key = _HIT_MEMO.key(self, outline)
        known = _HIT_MEMO.get(key)
        if known is not None:
            yield from known
            return
        kept: list[tuple[int, int, np.ndarray]] | None = []
        cells = 0
        for ra, c0, hit in self._compute_hit_blocks(outline):
            if kept is not None:
                cells += hit.size
                if cells <= _HitMemo.MAX_OUTLINE_CELLS:
                    hit.flags.writeable = False
                    kept.append((ra, c0, hit))
                else:  # a large shape: not kept
                    kept = None
            yield ra, c0, hit
        if kept is not None:
            _HIT_MEMO.put(key, kept, cells)

    def _compute_hit_blocks(self, outline: Outline) -> Iterator[tuple[int, int, np.ndarray]]:
        """The blocks of :meth:`_hit_blocks`, computed."""
        rows, cols = self.shape
        res = self.resolution
        x0, y0 = self.origin
        xmin, ymin, xmax, ymax = outline.extent()
        c0 = max(0, math.floor((xmin - x0) / res))
        c1 = min(cols - 1, math.floor((xmax - x0) / res))
        r0 = max(0, math.floor((ymin - y0) / res))
        r1 = min(rows - 1, math.floor((ymax - y0) / res))
        if c0 > c1 or r0 > r1:
            return
        lx = x0 + np.arange(c0, c1 + 1)[None, :] * res
        step = max(1, BLOCK_CELLS // (c1 - c0 + 1))
        for ra in range(r0, r1 + 1, step):
            ly = y0 + np.arange(ra, min(r1 + 1, ra + step))[:, None] * res
            if isinstance(outline, Disc):
                hit = _disc_hits(outline, lx, ly, res)
            else:
                hit = _polygon_hits(outline, lx, ly, res)
            yield ra, c0, hit

    def cells_of(self, outline: Outline) -> np.ndarray:
        """Flat indices of the cells whose squares overlap ``outline`` with positive area."""
        cols = self.shape[1]
        parts = [np.zeros(0, np.int64)]
        for ra, c0, hit in self._hit_blocks(outline):
            rr, cc = np.nonzero(hit)
            parts.append((rr + ra).astype(np.int64) * cols + (cc + c0))
        return np.concatenate(parts)

    def mark(self, outlines: Iterable[Outline], source: int | None = None) -> None:
        """Mark the cells of ``outlines`` occupied (remembered under ``source`` if given)."""
        if source is not None:
            idx = [self.cells_of(o) for o in outlines]
            flat = np.unique(np.concatenate(idx)) if idx else np.zeros(0, np.int64)
            self.occupied.reshape(-1)[flat] = True
            self.sources[source] = flat
            return
        for outline in outlines:
            for ra, c0, hit in self._hit_blocks(outline):
                self.occupied[ra : ra + hit.shape[0], c0 : c0 + hit.shape[1]] |= hit

    def occupied_by(self, body: int) -> np.ndarray:
        """(n, 2) cells marked for ``body`` (empty if it was not drawn as a source)."""
        flat = self.sources.get(body, np.zeros(0, np.int64))
        return np.column_stack(np.unravel_index(flat, self.shape))

    # -- output ----------------------------------------------------------------------------------
    def save_png(self, path: str | Path, path_cells: np.ndarray | None = None) -> None:
        """Write the grid as a PNG, north up: occupied black, free white, a path in red."""
        img = np.empty((*self.shape, 3), np.uint8)
        img[...] = np.where(self.occupied, np.uint8(0), np.uint8(255))[..., None]
        if path_cells is not None and len(path_cells):
            p = np.asarray(path_cells)
            img[p[:, 0], p[:, 1]] = (220, 30, 30)
        write_png(path, img[::-1])


class _HitMemo:
    """The hit blocks of outlines already drawn in this process (see
    :meth:`OccupancyGrid._hit_blocks`), keyed by the outline's and the grid's numbers (their
    bytes, so equal keys mean equal inputs bit for bit), least recently used dropped first.
    Bounded in entries and in cells held."""

    MAX_ENTRIES = 4096
    MAX_CELLS = 8_000_000
    """Cells (one byte each) held at most over all entries."""
    MAX_OUTLINE_CELLS = 200_000
    """Outlines covering more cells than this are not kept."""

    def __init__(self) -> None:
        self._blocks: dict[bytes, list[tuple[int, int, np.ndarray]]] = {}
        self._sizes: dict[bytes, int] = {}
        self.cells = 0
        self._lock = threading.Lock()  # grids may be drawn from more than one thread

    @staticmethod
    def key(grid: OccupancyGrid, outline: Outline) -> bytes:
        rows, cols = grid.shape
        head = np.array(
            [grid.origin[0], grid.origin[1], grid.resolution, rows, cols], dtype=float
        ).tobytes()
        if isinstance(outline, Disc):
            return b"d" + head + np.array([outline.cx, outline.cy, outline.radius]).tobytes()
        v = np.ascontiguousarray(outline.vertices, dtype=float)
        return b"p" + head + np.array(v.shape, dtype=float).tobytes() + v.tobytes()

    def get(self, key: bytes) -> list[tuple[int, int, np.ndarray]] | None:
        with self._lock:
            blocks = self._blocks.pop(key, None)
            if blocks is not None:  # most recently used last
                self._blocks[key] = blocks
            return blocks

    def put(self, key: bytes, blocks: list[tuple[int, int, np.ndarray]], cells: int) -> None:
        with self._lock:
            if key in self._blocks or cells > self.MAX_CELLS:
                return
            while self._blocks and (
                len(self._blocks) >= self.MAX_ENTRIES or self.cells + cells > self.MAX_CELLS
            ):
                old = next(iter(self._blocks))
                del self._blocks[old]
                self.cells -= self._sizes.pop(old)
            self._blocks[key] = blocks
            self._sizes[key] = cells
            self.cells += cells

    def clear(self) -> None:
        with self._lock:
            self._blocks.clear()
            self._sizes.clear()
            self.cells = 0


_HIT_MEMO = _HitMemo()


def _disc_hits(d: Disc, lx: np.ndarray, ly: np.ndarray, res: float) -> np.ndarray:
    """Cells (lower-left corners lx (1, n), ly (m, 1)) whose square overlaps the disc's
    interior, as an (m, n) mask."""
    nx = np.clip(d.cx, lx, lx + res)
    ny = np.clip(d.cy, ly, ly + res)
    hits: np.ndarray = (nx - d.cx) ** 2 + (ny - d.cy) ** 2 < (d.radius - _EPS) ** 2
    return hits


def _polygon_hits(p: Polygon, lx: np.ndarray, ly: np.ndarray, res: float) -> np.ndarray:
    """Separating-axis test of each cell square against a convex polygon (strict overlap);
    lower-left corners lx (1, n) and ly (m, 1), an (m, n) mask."""
    v = p.vertices
    xmin, ymin, xmax, ymax = p.extent()
    hit = ((lx < xmax - _EPS) & (lx + res > xmin + _EPS)) & (
        (ly < ymax - _EPS) & (ly + res > ymin + _EPS)
    )
    corners = v.tolist()  # plain floats: the same arithmetic, less overhead per edge
    n = len(corners)
    for i in range(n):
        ax, ay = corners[i]
        bx, by = corners[(i + 1) % n]
        nx, ny = by - ay, -(bx - ax)  # outward normal of a counter-clockwise edge
        norm = math.hypot(nx, ny)
        if norm < 1e-12:
            continue
        nx, ny = nx / norm, ny / norm
        edge = nx * ax + ny * ay
        # smallest projection of the square's corners on the normal
        low = nx * lx + ny * ly + min(0.0, nx * res) + min(0.0, ny * res)
        hit &= low < edge - _EPS
    return hit


def write_png(path: str | Path, rgb: np.ndarray) -> None:
    """Write an (h, w, 3) uint8 image as PNG with numpy and zlib only."""
    h, w, _ = rgb.shape
    rows = np.zeros((h, 1 + 3 * w), np.uint8)  # each row: filter byte 0, then the pixels
    rows[:, 1:] = rgb.reshape(h, 3 * w)

    def chunk(tag: bytes, data: bytes) -> bytes:
        body = tag + data
        return (
            struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)
        )

    png = b"\x89PNG\r\n\x1a\n"
    png += chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(rows.tobytes(), 6))
    png += chunk(b"IEND", b"")
    Path(path).write_bytes(png)


def save_cost_png(
    path: str | Path,
    cost: np.ndarray,
    path_cells: np.ndarray | None = None,
) -> None:
    """Write a cost grid as a PNG, north up: blocked black, cost 1 white, higher costs darker
    blue, a path in red."""
    finite = np.isfinite(cost)
    top = float(cost[finite].max()) if finite.any() else 1.0
    img = np.empty((*cost.shape, 3), np.uint8)
    img[..., 2] = 255
    for a in range(0, cost.shape[0], max(1, BLOCK_CELLS // max(1, cost.shape[1]))):
        block = slice(a, a + max(1, BLOCK_CELLS // max(1, cost.shape[1])))
        ok = finite[block]
        shade = np.zeros(ok.shape)
        if top > 1.0:
            shade[ok] = (cost[block][ok] - 1.0) / (top - 1.0)
        img[block, :, 0] = (255 * (1.0 - 0.8 * shade)).astype(np.uint8)
        img[block, :, 1] = (255 * (1.0 - 0.6 * shade)).astype(np.uint8)
    img[~finite] = 0
    if path_cells is not None and len(path_cells):
        p = np.asarray(path_cells)
        img[p[:, 0], p[:, 1]] = (220, 30, 30)
    write_png(path, img[::-1])


def bodies_extent(
    client: int, bodies: Sequence[int], pad: float = 0.0
) -> tuple[float, float, float, float]:
    """(xmin, ymin, xmax, ymax) around the AABBs of ``bodies`` (all their links), padded."""
    lo = np.full(2, np.inf)
    hi = np.full(2, -np.inf)
    for b in bodies:
        for link in range(-1, pbq.joint_count(client, b)):
            a, c = pbq.aabb(client, b, link)
            lo = np.minimum(lo, a[:2])
            hi = np.maximum(hi, c[:2])
    if not np.isfinite(lo).all():
        raise ValueError("no bodies to take the extent of")
    return float(lo[0] - pad), float(lo[1] - pad), float(hi[0] + pad), float(hi[1] + pad)


def rasterise(
    client: int,
    obstacles: Sequence[int],
    *,
    resolution: float = DEFAULT_RESOLUTION,
    band: ZBand = DEFAULT_BAND,
    extent: tuple[float, float, float, float] | None = None,
    movable: Sequence[int] = (),
    pad: float = 0.5,
    remember: bool = True,
) -> OccupancyGrid:
    """Occupancy grid of the collision shapes of ``obstacles`` (and ``movable``) in ``band``.

    ``extent`` defaults to the bounding rectangle of the obstacles, padded by ``pad``. Each
    body's cells are remembered (:attr:`OccupancyGrid.sources`) unless ``remember`` is False
    (then a shape is drawn straight into the grid, with no list of its cells).
    """
    if extent is None:
        extent = bodies_extent(client, list(obstacles) + list(movable), pad)
    grid = OccupancyGrid.empty(extent, resolution, band)
    for body in list(obstacles) + list(movable):
        grid.mark(body_outlines(client, body, band), source=body if remember else None)
    return grid
