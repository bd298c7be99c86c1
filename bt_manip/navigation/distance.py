"""Exact Euclidean distance transform of an occupancy grid, in integers and little memory.

:func:`squared_distances` gives, for every cell, the squared distance (in cells) from its centre
to the centre of the nearest occupied cell: an exact integer, stored as ``uint32`` when every
possible value fits (grids up to about 46,000 cells a side) and ``int64`` otherwise. It is the
separable algorithm of Meijster, Roerdink and Hesselink (2000): a pass down and up each column
for the distance to the nearest occupied cell in that column, then per row the lower envelope
of the parabolas ``(x - i)^2 + g(i)^2``, all in integer arithmetic, so the result is exact.

The output array is the only full-size allocation (4 bytes per cell on ordinary grids); the
row pass works in place with three row-sized buffers. From it,
``sqrt(d2) x resolution`` is the Euclidean distance that ``scipy.ndimage.distance_transform_edt``
would give, bit for bit (scipy sums the squared integer offsets in float64 and takes the square
root; the same float64 operations on the same integers give the same values).
"""

from __future__ import annotations

import numba
import numpy as np

from bt_manip.cache import Memo, bytes_key


def squared_distances_dtype(shape: tuple[int, int]) -> type[np.integer]:
    """The integer type :func:`squared_distances` uses for a grid of ``shape``."""
    rows, cols = shape
    # the column pass stores up to rows + cols (the "no obstacle" stand-in) before squaring
    biggest = max((rows - 1) ** 2 + (cols - 1) ** 2, rows + cols)
    return np.uint32 if biggest < 2**32 - 1 else np.int64


@numba.njit(cache=True)
def _columns(occupied: np.ndarray, out: np.ndarray, far: int) -> None:
    """Per cell, the distance (cells) to the nearest occupied cell of its column, ``far`` if
    none; rows are visited in order so that memory is read sequentially."""
    rows, cols = occupied.shape
    for c in range(cols):
        out[0, c] = 0 if occupied[0, c] else far
    for r in range(1, rows):
        for c in range(cols):
            if occupied[r, c]:
                out[r, c] = 0
            else:
                up = out[r - 1, c]
                out[r, c] = up + 1 if up < far else far
    for r in range(rows - 2, -1, -1):
        for c in range(cols):
            down = out[r + 1, c] + 1
            if down < out[r, c]:
                out[r, c] = down


@numba.njit(cache=True)
def _rows(out: np.ndarray) -> None:
    """Replace each row's column distances g by min over i of (x - i)^2 + g(i)^2, exactly."""
    rows, cols = out.shape
    g = np.empty(cols, np.int64)
    s = np.empty(cols, np.int64)
    t = np.empty(cols, np.int64)
    for r in range(rows):
        for x in range(cols):
            v = np.int64(out[r, x])
            g[x] = v * v
        q = 0
        s[0] = 0
        t[0] = 0
        for u in range(1, cols):
            while q >= 0 and (t[q] - s[q]) ** 2 + g[s[q]] > (t[q] - u) ** 2 + g[u]:
                q -= 1
            if q < 0:
                q = 0
                s[0] = u
            else:
                i = s[q]
                # first x at which parabola u is not above parabola i (floor division: exact)
                w = 1 + (u * u - i * i + g[u] - g[i]) // (2 * (u - i))
                if w < cols:
                    q += 1
                    s[q] = u
                    t[q] = w
        for u in range(cols - 1, -1, -1):
            i = s[q]
            out[r, u] = (u - i) ** 2 + g[i]
            if u == t[q]:
                q -= 1


def squared_distances(occupied: np.ndarray) -> np.ndarray | None:
    """Squared distance (cells^2) from each cell to the nearest occupied cell, or ``None`` if no
    cell is occupied. 0 in occupied cells.

    The distances of grids of up to :data:`MEMO_GRID_CELLS` cells are remembered for the
    process under the grid's shape and occupied cells (the walls and furniture of a world give
    the same grid in every episode); the caller gets its own copy."""
    occ = np.ascontiguousarray(occupied, dtype=bool)
    if occ.ndim != 2:
        raise ValueError("occupied must be a 2-D array")
    if not occ.any():
        return None
    key = None
    if occ.size <= MEMO_GRID_CELLS:
        key = bytes_key(np.array(occ.shape, np.int64).tobytes() + np.packbits(occ).tobytes())
        known = _DISTANCE_MEMO.get(key)
        if known is not None:
            return known.copy()
    rows, cols = occ.shape
    out = np.empty(occ.shape, squared_distances_dtype(occ.shape))
    _columns(occ, out, rows + cols)
    _rows(out)
    if key is not None:
        _DISTANCE_MEMO.put(key, out.copy())
    return out


MEMO_GRID_CELLS = 1 << 20
"""Grids of more cells than this are not remembered."""

_DISTANCE_MEMO: Memo[np.ndarray] = Memo(16)
"""Squared distances of the grids seen in this process (at most 16 grids of at most
:data:`MEMO_GRID_CELLS` cells: about 70 MB at most, 5 MB for a house)."""
