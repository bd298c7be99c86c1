"""The compiled A* searches behind :mod:`bt_manip.navigation.astar`.

Two open lists, one contract. Both take a C-contiguous float32 grid (``inf`` = blocked, finite
costs > 0), flat start and goal indices, and return ``(parent, g_goal, expanded)``:
``parent[i]`` is the predecessor of cell ``i`` on its best known path (valid only for reached
cells; -1 for the start), ``g_goal`` the cost of the cheapest path (``inf`` if none),
``expanded`` the number of cell expansions.

- :func:`search_buckets` (used when the costs span a modest range, as on occupancy grids):
  the open list is a circular array of f-buckets of fixed width, each a last-in first-out
  stack. Push and pop are O(1). Because a bucket is not sorted, a cell may be expanded before
  its best g is known; it is then expanded again when g improves (label correcting), and the
  search stops only when no open entry can still beat the goal's g, so the cost is exact.
- :func:`search_heap`: a binary heap ordered by f (rounded down to a tiny quantum so that
  equal-cost paths tie exactly despite floating-point rounding), then by larger g. Used for
  grids whose cost range would make the bucket array too long.

Both use the octile distance (Manhattan without diagonals) times the smallest cost as the
heuristic: admissible and consistent for these moves. An improvement of g smaller than
``KEEP`` (1e-13 relative) is treated as a tie, so rounding noise between equal-cost paths does
not trigger re-expansions.
"""

from __future__ import annotations

import math
import mmap

import numba
import numpy as np

KEEP = 1.0 - 1e-13
"""A new g must be below ``KEEP x`` the known g to count as an improvement."""

# Neighbour order: four sides first, then the four diagonals.
DR = np.array([-1, 1, 0, 0, -1, -1, 1, 1], dtype=np.int64)
DC = np.array([0, 0, -1, 1, -1, 1, -1, 1], dtype=np.int64)


@numba.njit(cache=True, inline="always")
def _h(r: int, c: int, gr: int, gc: int, diagonal: bool, hmin: float) -> float:
    ar = abs(r - gr)
    ac = abs(c - gc)
    if not diagonal:
        return (ar + ac) * hmin
    if ar > ac:
        return (ar - ac + math.sqrt(2.0) * ac) * hmin
    return (ac - ar + math.sqrt(2.0) * ar) * hmin


@numba.njit(cache=True)
def _max_finite_bits(bits: np.ndarray) -> int:
    """Largest bit pattern below +inf among float32 values viewed as int32 (0 if none).

    For non-negative floats the int32 view orders like the values, so this is the largest
    finite value's pattern; integer arithmetic lets the loop vectorise.
    """
    hi = np.int32(0)
    for i in range(bits.shape[0]):
        b = bits[i]
        b = b if b < np.int32(0x7F800000) else np.int32(0)
        hi = max(hi, b)
    return hi  # type: ignore[return-value]  # numba body: the int32 comes back as an int


def cost_range(grid: np.ndarray) -> tuple[float, float]:
    """Smallest and largest finite cost of a float32 grid.

    Raises ``ValueError`` if a value is NaN or not positive.
    """
    lo = float(grid.min())
    if not lo > 0.0:  # NaN propagates through min()
        raise ValueError("cost values must be positive (inf for blocked), without NaN")
    hi = np.int32(_max_finite_bits(grid.reshape(-1).view(np.int32))).view(np.float32)
    return lo, float(hi)


def scratch(cells: int) -> tuple[np.ndarray, np.ndarray]:
    """Fresh ``g`` and ``parent`` arrays for a search over ``cells`` cells.

    ``g`` is all zeros, read as "not reached" (every reached cell but the start has g > 0), so
    both can live in an anonymous memory map: the system hands out zero pages on first touch,
    in small pages (numpy would ask for huge pages on arrays this large), and a search that
    explores a small part of a large grid keeps only that part resident. ``parent`` is read
    only for reached cells.
    """
    g = np.frombuffer(mmap.mmap(-1, max(1, cells) * 8), np.float64)
    parent = np.frombuffer(mmap.mmap(-1, max(1, cells) * 4), np.int32)
    return g[:cells], parent[:cells]


@numba.njit(cache=True, inline="always")
def _improves(new_g: float, known: float, is_start: bool) -> bool:
    """Whether ``new_g`` beats a cell's stored g (0 = not reached, except at the start)."""
    if known == 0.0:
        return not is_start
    return new_g < known * KEEP


@numba.njit(cache=True)
def trace(parent: np.ndarray, start: int, goal: int, cols: int) -> np.ndarray:
    """The (row, col) cells from ``start`` to ``goal`` following ``parent`` links."""
    n = 1
    node = goal
    while node != start:
        node = parent[node]
        n += 1
    out = np.empty((n, 2), np.int64)
    node = goal
    for i in range(n - 1, -1, -1):
        out[i, 0] = node // cols
        out[i, 1] = node % cols
        node = parent[node]
    return out


@numba.njit(cache=True)
def _doubled(a: np.ndarray) -> np.ndarray:
    """A copy of ``a`` with twice the room (the new half is left uninitialised)."""
    out = np.empty(a.shape[0] * 2, a.dtype)
    out[: a.shape[0]] = a
    return out


@numba.njit(cache=True)
def search_buckets(
    cost: np.ndarray,
    start: int,
    goal: int,
    diagonal: bool,
    hmin: float,
    delta: float,
    span: int,
    g: np.ndarray,
    parent: np.ndarray,
) -> tuple[np.ndarray, float, int]:
    """A* with f-buckets of width ``delta`` in a circular array of ``span`` buckets.

    ``span`` must exceed the largest f increase along one move divided by ``delta``, plus 2.
    ``g`` and ``parent`` are the caller's scratch arrays (see :func:`scratch`).
    """
    rows, cols = cost.shape
    flat = cost.ravel()
    gr = goal // cols
    gc = goal % cols
    sqrt2 = math.sqrt(2.0)
    nmoves = 8 if diagonal else 4
    inv_delta = 1.0 / delta

    heads = np.full(span, -1, np.int32)  # first pool slot of each bucket
    pn = np.empty(4096, np.int32)  # pool: cell, g at push time, next slot in the bucket
    pg = np.empty(4096, np.float64)
    pnext = np.empty(4096, np.int32)

    g[start] = 0.0
    parent[start] = -1
    cur = np.int64(math.floor(_h(start // cols, start % cols, gr, gc, diagonal, hmin) * inv_delta))
    pn[0] = start
    pg[0] = 0.0
    pnext[0] = -1
    heads[cur % span] = 0
    used = 1
    free = -1
    n_open = 1
    expanded = 0
    g_goal = np.inf

    while n_open > 0:
        b = cur % span
        while heads[b] == -1:
            cur += 1
            b += 1
            if b == span:
                b = 0  # type: ignore[assignment]  # numba body: numba unifies int64 and int
        if cur * delta >= g_goal:
            break  # every open entry has f >= g_goal
        slot = heads[b]
        heads[b] = pnext[slot]
        n_open -= 1
        node = pn[slot]
        gn = pg[slot]
        pnext[slot] = free
        free = slot
        if gn > g[node]:
            continue  # stale entry
        r = node // cols
        c = node % cols
        if g_goal < np.inf and gn + _h(r, c, gr, gc, diagonal, hmin) >= g_goal * KEEP:
            continue  # cannot lead to a cheaper path to the goal
        expanded += 1
        for k in range(nmoves):
            nr = r + DR[k]
            nc = c + DC[k]
            if nr < 0 or nr >= rows or nc < 0 or nc >= cols:
                continue
            nb = nr * cols + nc
            w = flat[nb]
            if w == np.inf:
                continue
            if k >= 4:
                if flat[nr * cols + c] == np.inf or flat[r * cols + nc] == np.inf:
                    continue  # diagonal past a blocked corner
                ng_ = gn + sqrt2 * w
            else:
                ng_ = gn + w
            if not _improves(ng_, g[nb], nb == start):
                continue
            g[nb] = ng_
            parent[nb] = node
            if nb == goal:
                g_goal = ng_
                continue
            f = ng_ + _h(nr, nc, gr, gc, diagonal, hmin)
            if f >= g_goal * KEEP:
                continue
            kb = np.int64(math.floor(f * inv_delta))
            kb = max(kb, cur)
            if free != -1:
                s = free
                free = pnext[s]
            else:
                if used == pn.shape[0]:
                    pn, pg, pnext = _doubled(pn), _doubled(pg), _doubled(pnext)
                s = used
                used += 1
            kb = kb % span
            pn[s] = nb
            pg[s] = ng_
            pnext[s] = heads[kb]
            heads[kb] = s
            n_open += 1
    return parent, g_goal, expanded


@numba.njit(cache=True, inline="always")
def _before(fa: float, ga: float, fb: float, gb: float) -> bool:
    """Heap order: smaller f first; on equal f, larger g (deeper) first."""
    return fa < fb or (fa == fb and ga > gb)


@numba.njit(cache=True)
def search_heap(
    cost: np.ndarray,
    start: int,
    goal: int,
    diagonal: bool,
    hmin: float,
    quantum: float,
    g: np.ndarray,
    parent: np.ndarray,
) -> tuple[np.ndarray, float, int]:
    """A* with a binary heap on (f rounded down to ``quantum``, larger g first).

    The returned cost exceeds the optimum by less than ``quantum``. ``g`` and ``parent`` are
    the caller's scratch arrays (see :func:`scratch`).
    """
    rows, cols = cost.shape
    flat = cost.ravel()
    gr = goal // cols
    gc = goal % cols
    sqrt2 = math.sqrt(2.0)
    nmoves = 8 if diagonal else 4
    inv_q = 1.0 / quantum

    hf = np.empty(1024, np.float64)
    hg = np.empty(1024, np.float64)
    hn = np.empty(1024, np.int32)
    g[start] = 0.0
    parent[start] = -1
    hf[0] = math.floor(_h(start // cols, start % cols, gr, gc, diagonal, hmin) * inv_q)
    hg[0] = 0.0
    hn[0] = start
    size = 1
    expanded = 0

    while size > 0:
        g_top = hg[0]
        node = hn[0]
        size -= 1
        if size > 0:  # move the last entry down from the root
            lf = hf[size]
            lg = hg[size]
            ln = hn[size]
            i = 0
            while True:
                child = 2 * i + 1
                if child >= size:
                    break
                if child + 1 < size and _before(hf[child + 1], hg[child + 1], hf[child], hg[child]):
                    child += 1
                if not _before(hf[child], hg[child], lf, lg):
                    break
                hf[i] = hf[child]
                hg[i] = hg[child]
                hn[i] = hn[child]
                i = child
            hf[i] = lf
            hg[i] = lg
            hn[i] = ln
        if g_top > g[node]:
            continue  # stale entry
        if node == goal:
            return parent, g_top, expanded
        expanded += 1
        r = node // cols
        c = node % cols
        for k in range(nmoves):
            nr = r + DR[k]
            nc = c + DC[k]
            if nr < 0 or nr >= rows or nc < 0 or nc >= cols:
                continue
            nb = nr * cols + nc
            w = flat[nb]
            if w == np.inf:
                continue
            if k >= 4:
                if flat[nr * cols + c] == np.inf or flat[r * cols + nc] == np.inf:
                    continue
                ng_ = g_top + sqrt2 * w
            else:
                ng_ = g_top + w
            if not _improves(ng_, g[nb], nb == start):
                continue
            g[nb] = ng_
            parent[nb] = node
            nf_ = math.floor((ng_ + _h(nr, nc, gr, gc, diagonal, hmin)) * inv_q)
            if size == hf.shape[0]:
                hf, hg, hn = _doubled(hf), _doubled(hg), _doubled(hn)
            i = size
            size += 1
            while i > 0:  # move the new entry up
                p = (i - 1) >> 1
                if not _before(nf_, ng_, hf[p], hg[p]):
                    break
                hf[i] = hf[p]
                hg[i] = hg[p]
                hn[i] = hn[p]
                i = p
            hf[i] = nf_
            hg[i] = ng_
            hn[i] = nb
    return parent, np.inf, expanded
