"""The compiled A* searches behind :mod:`bt_manip.navigation.astar`.

Two open lists, one contract. Both take a C-contiguous float32 grid (``inf`` = blocked, finite
costs > 0), flat start and goal indices and a :class:`Scratch`, and return
``(g_goal, expanded)``: the cost of the cheapest path (``inf`` if none) and the number of cell
expansions; :func:`trace` then reads the path from the scratch's ``parent`` moves.

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

Scratch memory. ``g`` is stored as the bits of the float64 value XOR those of ``+inf``, so a
zero word reads as ``+inf``, "not reached" (the start, g = 0, is stored as the bits of inf):
zero pages are an empty search, and a blocked neighbour (step cost inf) can never improve on
it. ``parent`` holds the move (0-7, see ``DR``/``DC``) by which each reached cell was last
improved, one byte per cell. The sign bit of a g word, never set by a g >= 0, is the bucket
search's mark that it expanded the cell with that g (:data:`CLOSED`); storing an improved g
clears it. Each search records, per row, the first and last column of the cells it
expanded; it wrote ``g`` only in those cells' 3 x 3 neighbourhoods, and a search asked to
clean up sets that part back to zero before it returns, so the next search can reuse the same
memory without touching the rest of the grid.

The bucket search's loop (:func:`_bucket_rounds`, :func:`_relax`) is compiled without numba's
runtime: it allocates nothing and counts no references, and its eight moves are written out
one by one, so an expansion costs no array traffic beyond the grid, ``g`` and the pool. Its
array reads and writes skip numba's wrap of negative indices (every index is inside its array:
a move that would leave the grid is offered to the expanded cell itself), a pool entry is one
int64 (the cell and the next slot of its bucket), and the cell pushed last onto the current
bucket, the next to be expanded, waits outside the pool.

Arrays are copied by loops, never by assigning one array to a slice of another: numba checks
such an assignment's shapes and compiles, for its error message, its string formatting (join,
str of integers), seconds on the first run after an install, for a copy LLVM emits the same
either way.
"""

from __future__ import annotations

import math
import mmap
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic
from numba.np.arrayobj import load_item, store_item

KEEP = 1.0 - 1e-13
"""A new g must be below ``KEEP x`` the known g to count as an improvement."""

# Neighbour order: four sides first, then the four diagonals.
DR = np.array([-1, 1, 0, 0, -1, -1, 1, 1], dtype=np.int64)
DC = np.array([0, 0, -1, 1, -1, 1, -1, 1], dtype=np.int64)
# the two sides a diagonal move passes: (up or down, left or right) for moves 4-7
SIDE_ROW = np.array([0, 0, 1, 1], dtype=np.int64)
SIDE_COL = np.array([2, 3, 2, 3], dtype=np.int64)
INF_BITS = np.int64(0x7FF0000000000000)
"""Bits of float64 ``+inf``: stored g words are the value's bits XOR these."""
CLOSED = np.int64(-0x8000000000000000)
"""The sign bit of a g word: set when the bucket search expands the cell with its stored g."""


@intrinsic
def _bits_to_float(typingctx, bits):  # type: ignore[no-untyped-def]  # numba intrinsic
    """The float64 whose bits are the int64 ``bits``."""
    sig = types.float64(types.int64)

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        return builder.bitcast(args[0], ir.DoubleType())

    return sig, codegen


@intrinsic
def _float_to_bits(typingctx, value):  # type: ignore[no-untyped-def]  # numba intrinsic
    """The bits of the float64 ``value`` as an int64."""
    sig = types.int64(types.float64)

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        return builder.bitcast(args[0], ir.IntType(64))

    return sig, codegen


@intrinsic
def _prefetch(typingctx, arr, idx):  # type: ignore[no-untyped-def]  # numba intrinsic
    """Ask the processor to bring ``arr[idx]`` into cache (a hint: never faults)."""
    sig = types.void(arr, idx)

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        arrty = signature.args[0]
        ary = context.make_array(arrty)(context, builder, args[0])
        ptr = cgutils.get_item_pointer(context, builder, arrty, ary, [args[1]], wraparound=False)
        i8p = ir.IntType(8).as_pointer()
        i32 = ir.IntType(32)
        fnty = ir.FunctionType(ir.VoidType(), [i8p, i32, i32, i32])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.prefetch.p0")
        # read, keep in all cache levels, data cache
        builder.call(fn, [builder.bitcast(ptr, i8p), i32(0), i32(3), i32(1)])
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _get(typingctx, arr, idx):  # type: ignore[no-untyped-def]  # numba intrinsic
    """``arr[idx]`` for a 1-D array and an index known to be inside it (no negative wrap)."""
    sig = arr.dtype(arr, idx)

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        arrty, idxty = signature.args
        ary = context.make_array(arrty)(context, builder, args[0])
        i = context.cast(builder, args[1], idxty, types.intp)
        ptr = cgutils.get_item_pointer(context, builder, arrty, ary, [i], wraparound=False)
        return load_item(context, builder, arrty, ptr)

    return sig, codegen


@intrinsic
def _put(typingctx, arr, idx, value):  # type: ignore[no-untyped-def]  # numba intrinsic
    """``arr[idx] = value`` for a 1-D array and an index known to be inside it."""
    sig = types.void(arr, idx, value)

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        arrty, idxty, valty = signature.args
        ary = context.make_array(arrty)(context, builder, args[0])
        i = context.cast(builder, args[1], idxty, types.intp)
        ptr = cgutils.get_item_pointer(context, builder, arrty, ary, [i], wraparound=False)
        store_item(context, builder, arrty, context.cast(builder, args[2], valty, arrty.dtype), ptr)
        return context.get_dummy_value()

    return sig, codegen


@numba.njit(cache=True, inline="always")
def _prefetch_rows(g: np.ndarray, flat: np.ndarray, q: int, cols: int) -> None:
    """Prefetch the rows above and below cell ``q`` of ``g`` and the cost grid."""
    _prefetch(g, q - cols)  # type: ignore[call-arg]  # numba body, as for _load_g
    _prefetch(g, q + cols)  # type: ignore[call-arg]
    _prefetch(flat, q - cols)  # type: ignore[call-arg]
    _prefetch(flat, q + cols)  # type: ignore[call-arg]


@numba.njit(cache=True, inline="always")
def _load_g(g: np.ndarray, i: int) -> float:
    """g of cell ``i`` (``inf`` when not reached), whether or not it is marked closed."""
    # numba body: mypy reads the intrinsic as taking the typing context too
    return abs(_bits_to_float(_get(g, i) ^ INF_BITS))  # type: ignore[call-arg, no-any-return]


@numba.njit(cache=True, inline="always")
def _store_g(g: np.ndarray, i: int, value: float) -> None:
    _put(g, i, _float_to_bits(value) ^ INF_BITS)  # type: ignore[call-arg]  # numba body, as above


@numba.njit(cache=True, inline="always")
def _h(r: int, c: int, gr: int, gc: int, diagonal: bool, hmin: float) -> float:
    ar = abs(r - gr)
    ac = abs(c - gc)
    if not diagonal:
        return (ar + ac) * hmin
    hi = max(ar, ac)
    lo = min(ar, ac)
    return (hi - lo + math.sqrt(2.0) * lo) * hmin


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


def _zero_pages(nbytes: int, huge: bool) -> mmap.mmap:
    """An anonymous map of ``nbytes`` zero bytes (resident only where touched)."""
    area = mmap.mmap(-1, max(1, nbytes))
    if huge and hasattr(mmap, "MADV_HUGEPAGE"):
        area.madvise(mmap.MADV_HUGEPAGE)
    return area


@dataclass
class Scratch:
    """Per-cell memory of a search over up to ``cells`` cells and ``rows`` rows.

    ``g`` (int64 words, see the module notes) and ``parent`` (uint8 moves) live in anonymous
    memory maps: the system hands out zero pages on first touch, so a search that explores a
    small part of a large grid keeps only that part resident. ``lo``/``hi`` are, per row, the
    first and last column of the cells the current search expanded (``lo > hi``: none).
    """

    cells: int
    rows: int
    g: np.ndarray
    parent: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    @classmethod
    def new(cls, cells: int, rows: int, huge: bool = False) -> Scratch:
        """Fresh scratch; ``huge`` asks for huge pages (fewer, larger pages for a kept one)."""
        g = np.frombuffer(_zero_pages(cells * 8, huge), np.int64)[:cells]
        parent = np.frombuffer(_zero_pages(cells, huge), np.uint8)[:cells]
        lo = np.full(max(1, rows), np.iinfo(np.int32).max, np.int32)
        hi = np.full(max(1, rows), -1, np.int32)
        return cls(cells, rows, g, parent, lo, hi)

    def fits(self, cells: int, rows: int) -> bool:
        return self.cells >= cells and self.rows >= rows


@numba.njit(cache=True, inline="always")
def _mark(lo: np.ndarray, hi: np.ndarray, r: int, c: int) -> None:
    """Remember that the search expanded (r, c): it may have written g in the 3 x 3 cells
    around it."""
    if c < _get(lo, r):  # type: ignore[call-arg]  # numba body, as for _load_g
        _put(lo, r, c)  # type: ignore[call-arg]
    if c > _get(hi, r):  # type: ignore[call-arg]
        _put(hi, r, c)  # type: ignore[call-arg]


@numba.njit(cache=True)
def _clean(g: np.ndarray, lo: np.ndarray, hi: np.ndarray, rows: int, cols: int, zero: bool) -> None:
    """Forget the marks; with ``zero``, also set the g words the search may have written
    back to 0: in row r, the columns of the marks of rows r - 1 to r + 1, widened by one."""
    top = np.iinfo(np.int32).max
    above_lo, above_hi = top, -1  # the marks of row r - 1, before they were reset
    for r in range(rows):
        here_lo, here_hi = lo[r], hi[r]
        below_lo, below_hi = (lo[r + 1], hi[r + 1]) if r + 1 < rows else (top, -1)
        first = max(min(above_lo, here_lo, below_lo) - 1, 0)
        last = min(max(above_hi, here_hi, below_hi) + 1, cols - 1)
        if zero and last >= first:
            g[r * cols + first : r * cols + last + 1] = 0
        above_lo, above_hi = here_lo, here_hi
        lo[r] = top
        hi[r] = -1


@numba.njit(cache=True)
def trace(parent: np.ndarray, start: int, goal: int, cols: int) -> np.ndarray:
    """The (row, col) cells from ``start`` to ``goal`` following the ``parent`` moves."""
    n = 1
    node = goal
    while node != start:
        k = parent[node]
        node -= DR[k] * cols + DC[k]
        n += 1
    out = np.empty((n, 2), np.int64)
    node = goal
    for i in range(n - 1, -1, -1):
        out[i, 0] = node // cols
        out[i, 1] = node % cols
        if i > 0:
            k = parent[node]
            node -= DR[k] * cols + DC[k]
    return out


@numba.njit(cache=True)
def _doubled(a: np.ndarray) -> np.ndarray:
    """A copy of ``a`` with twice the room (the new half is left uninitialised)."""
    out = np.empty(a.shape[0] * 2, a.dtype)
    for i in range(a.shape[0]):  # a loop, not a slice copy: see the module's docstring
        out[i] = a[i]
    return out


@numba.njit(cache=True, inline="always")
def _move_costs(
    flat: np.ndarray,
    node: int,
    r: int,
    c: int,
    rows: int,
    cols: int,
    diagonal: bool,
    off: np.ndarray,
    w8: np.ndarray,
) -> int:
    """Fill ``w8[k]`` with the cost of the cell entered by move k (inf if not allowed).

    A diagonal move is allowed only when both side cells beside it are free. Returns the
    number of moves looked at (4 or 8).
    """
    inf = np.inf
    if r == 0 or r == rows - 1 or c == 0 or c == cols - 1:
        for k in range(4):
            nr = r + DR[k]
            nc = c + DC[k]
            if nr < 0 or nr >= rows or nc < 0 or nc >= cols:
                w8[k] = inf
            else:
                w8[k] = flat[node + off[k]]
    else:
        for k in range(4):
            w8[k] = flat[node + off[k]]
    if not diagonal:
        return 4
    for k in range(4, 8):
        if w8[SIDE_ROW[k - 4]] == inf or w8[SIDE_COL[k - 4]] == inf:
            w8[k] = inf
        else:
            w8[k] = flat[node + off[k]]
    return 8


_NO_REFCOUNT: dict[str, Any] = {"_nrt": False}
"""numba option: compile without the runtime (no reference counting; no allocation inside)."""

_LOW = np.int64(0xFFFFFFFF)

# Indices into the bucket search's state vectors (it runs in rounds between pool growths).
_CUR, _USED, _FREE, _OPEN, _EXPANDED = 0, 1, 2, 3, 4
_G_GOAL, _BOUND = 0, 1


@numba.njit(cache=True, **_NO_REFCOUNT)
def _relax(
    k: int,
    nb: int,
    nr: int,
    nc: int,
    ng_: float,
    g: np.ndarray,
    parent: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    heads: np.ndarray,
    pool: np.ndarray,
    goal: int,
    gr: int,
    gc: int,
    diagonal: bool,
    hmin: float,
    inv_delta: float,
    mask: int,
    cur: int,
    free: int,
    used: int,
    n_open: int,
    g_goal: float,
    bound: float,
    pending: int,
) -> tuple[int, int, int, float, float, int]:
    """Offer cell ``nb`` (row ``nr``, col ``nc``) the cost ``ng_`` by move ``k``.

    ``nb`` must be a cell of the grid (a move that leaves the grid offers inf to the expanded
    cell itself: its g is read, never beaten). If ``ng_`` beats the stored g, store it and
    push the cell into its f-bucket (the goal is not pushed: it sets the bound instead). A
    cell bound for the current bucket becomes the ``pending`` one instead, the one pushed
    there before it going into the pool: the pending cell is the top of that bucket, the
    next to be expanded, and skips the pool. Returns the updated ``(free, used, n_open,
    g_goal, bound, pending)``. Compiled without reference
    counting, like its caller, so that passing the arrays costs nothing.
    """
    # inf (a blocked move) never beats a stored g; an unreached cell reads as inf
    if ng_ < _load_g(g, nb) * KEEP:
        _store_g(g, nb, ng_)
        _put(parent, nb, k)  # type: ignore[call-arg]  # numba body, as for _load_g
        if nb == goal:
            return free, used, n_open, ng_, ng_ * KEEP, pending
        f = ng_ + _h(nr, nc, gr, gc, diagonal, hmin)
        if f < bound:
            n_open += 1
            key = max(math.floor(f * inv_delta), cur)
            if key == cur:
                nb, pending = pending, nb
                if nb == -1:
                    return free, used, n_open, g_goal, bound, pending
            free, used = _push(heads, pool, key & mask, nb, free, used)
    return free, used, n_open, g_goal, bound, pending


@numba.njit(cache=True, inline="always")
def _push(
    heads: np.ndarray, pool: np.ndarray, b: int, cell: int, free: int, used: int
) -> tuple[int, int]:
    """Push ``cell`` on top of bucket ``b`` in a free slot of the pool or a new one; returns
    the updated ``(free, used)``."""
    if free != -1:
        s = free
        free = _get(pool, s) >> 32  # type: ignore[call-arg]  # numba body, as for _load_g
    else:
        s = used
        used += 1
    _put(pool, s, cell | (np.int64(_get(heads, b)) << 32))  # type: ignore[call-arg]
    _put(heads, b, s)  # type: ignore[call-arg]
    return free, used


@numba.njit(cache=True, **_NO_REFCOUNT)
def _bucket_rounds(
    flat: np.ndarray,
    rows: int,
    cols: int,
    start: int,
    goal: int,
    diagonal: bool,
    hmin: float,
    delta: float,
    mask: int,
    g: np.ndarray,
    parent: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    heads: np.ndarray,
    pool: np.ndarray,
    ints: np.ndarray,
    floats: np.ndarray,
) -> bool:
    """Run the bucket search until it ends (True) or its pool may run out of slots (False).

    ``flat`` is the cost grid as one row-major vector of ``rows x cols``. A pool entry is one
    int64: the cell in the low 32 bits, the next slot of its bucket (or of the free list) in
    the high 32 bits (-1: none). The pool and the state vectors are the caller's. The
    function allocates nothing and is compiled without reference counting (``_nrt=False``):
    the moves are written out one by one (no per-move arrays), :func:`_relax` takes the
    arrays at no cost, and the array reads and writes skip numba's negative-index wrap.
    """
    gr = goal // cols
    gc = goal % cols
    sqrt2 = math.sqrt(2.0)
    inv_delta = 1.0 / delta
    inv_cols = 1.0 / cols
    inf = np.inf
    room = pool.shape[0] - 9  # an expansion pushes at most 8 entries, and the pending one
    cur = ints[_CUR]
    used = ints[_USED]
    free = ints[_FREE]
    n_open = ints[_OPEN]
    expanded = ints[_EXPANDED]
    g_goal = floats[_G_GOAL]
    bound = floats[_BOUND]  # g_goal x KEEP: what a path through an entry must beat
    pending = -1  # a cell on top of the current bucket, kept out of the pool
    done = True
    while n_open > 0:
        if used > room:
            done = False
            break
        if pending != -1:
            if cur * delta >= g_goal:
                break  # every open entry has f >= g_goal
            node = pending
            pending = -1
            n_open -= 1
            nxt: int = _get(heads, cur & mask)  # type: ignore[call-arg]  # numba body, as for _load_g
        else:
            b = cur & mask
            while _get(heads, b) == -1:  # type: ignore[call-arg]
                cur += 1
                b = cur & mask
            if cur * delta >= g_goal:
                break  # every open entry has f >= g_goal
            slot: int = _get(heads, b)  # type: ignore[call-arg]
            entry = _get(pool, slot)  # type: ignore[call-arg]
            nxt = entry >> 32
            _put(heads, b, nxt)  # type: ignore[call-arg]
            _put(pool, slot, np.int64(free) << 32)  # type: ignore[call-arg]
            free = slot
            n_open -= 1
            node = entry & _LOW
        if nxt != -1:  # likely the next pop: start loading its rows
            _prefetch_rows(g, flat, _get(pool, nxt) & _LOW, cols)  # type: ignore[call-arg]
        word = _get(g, node)  # type: ignore[call-arg]
        if word & CLOSED:
            continue  # expanded already with this g: a stale entry
        gn = _bits_to_float(word ^ INF_BITS)  # type: ignore[call-arg]
        # row and column without an integer division: the float quotient is off by at
        # most one, and the remainder says which way
        r = np.int64(node * inv_cols)
        c = node - r * cols
        if c < 0:
            r -= 1
            c += cols
        elif c >= cols:
            r += 1
            c -= cols
        if bound < inf and gn + _h(r, c, gr, gc, diagonal, hmin) >= bound:
            continue  # cannot lead to a cheaper path to the goal
        _put(g, node, word | CLOSED)  # type: ignore[call-arg]
        _mark(lo, hi, r, c)
        expanded += 1
        # the four side cells and their costs; outside the grid the cost is inf and the
        # cell is the expanded one itself (inf never beats its g: nothing outside is read)
        up = node - cols
        down = node + cols
        left = node - 1
        right = node + 1
        if r == 0 or r == rows - 1 or c == 0 or c == cols - 1:
            wu = wd = wl = wr = inf
            if r > 0:
                wu = _get(flat, up)  # type: ignore[call-arg]  # numba body, as for _load_g
            else:
                up = node
            if r < rows - 1:
                wd = _get(flat, down)  # type: ignore[call-arg]
            else:
                down = node
            if c > 0:
                wl = _get(flat, left)  # type: ignore[call-arg]
            else:
                left = node
            if c < cols - 1:
                wr = _get(flat, right)  # type: ignore[call-arg]
            else:
                right = node
        else:
            wu = _get(flat, up)  # type: ignore[call-arg]
            wd = _get(flat, down)  # type: ignore[call-arg]
            wl = _get(flat, left)  # type: ignore[call-arg]
            wr = _get(flat, right)  # type: ignore[call-arg]
        # moves in the order of DR/DC: up, down, left, right, then the diagonals, each
        # allowed only when both side cells beside it are free; a move's index is an int64,
        # not a literal: numba would compile _relax once per literal (eight times)
        free, used, n_open, g_goal, bound, pending = _relax(
            np.int64(0), up, r - 1, c, gn + wu, g, parent, lo, hi, heads, pool,
            goal, gr, gc, diagonal, hmin, inv_delta, mask, cur,
            free, used, n_open, g_goal, bound, pending,
        )  # fmt: skip
        free, used, n_open, g_goal, bound, pending = _relax(
            np.int64(1), down, r + 1, c, gn + wd, g, parent, lo, hi, heads, pool,
            goal, gr, gc, diagonal, hmin, inv_delta, mask, cur,
            free, used, n_open, g_goal, bound, pending,
        )  # fmt: skip
        free, used, n_open, g_goal, bound, pending = _relax(
            np.int64(2), left, r, c - 1, gn + wl, g, parent, lo, hi, heads, pool,
            goal, gr, gc, diagonal, hmin, inv_delta, mask, cur,
            free, used, n_open, g_goal, bound, pending,
        )  # fmt: skip
        free, used, n_open, g_goal, bound, pending = _relax(
            np.int64(3), right, r, c + 1, gn + wr, g, parent, lo, hi, heads, pool,
            goal, gr, gc, diagonal, hmin, inv_delta, mask, cur,
            free, used, n_open, g_goal, bound, pending,
        )  # fmt: skip
        if diagonal:
            if wu != inf and wl != inf:
                free, used, n_open, g_goal, bound, pending = _relax(
                    np.int64(4), node - cols - 1, r - 1, c - 1,
                    gn + sqrt2 * _get(flat, node - cols - 1),  # type: ignore[call-arg]
                    g, parent, lo, hi, heads, pool,
                    goal, gr, gc, diagonal, hmin, inv_delta, mask, cur,
                    free, used, n_open, g_goal, bound, pending,
                )  # fmt: skip
            if wu != inf and wr != inf:
                free, used, n_open, g_goal, bound, pending = _relax(
                    np.int64(5), node - cols + 1, r - 1, c + 1,
                    gn + sqrt2 * _get(flat, node - cols + 1),  # type: ignore[call-arg]
                    g, parent, lo, hi, heads, pool,
                    goal, gr, gc, diagonal, hmin, inv_delta, mask, cur,
                    free, used, n_open, g_goal, bound, pending,
                )  # fmt: skip
            if wd != inf and wl != inf:
                free, used, n_open, g_goal, bound, pending = _relax(
                    np.int64(6), node + cols - 1, r + 1, c - 1,
                    gn + sqrt2 * _get(flat, node + cols - 1),  # type: ignore[call-arg]
                    g, parent, lo, hi, heads, pool,
                    goal, gr, gc, diagonal, hmin, inv_delta, mask, cur,
                    free, used, n_open, g_goal, bound, pending,
                )  # fmt: skip
            if wd != inf and wr != inf:
                free, used, n_open, g_goal, bound, pending = _relax(
                    np.int64(7), node + cols + 1, r + 1, c + 1,
                    gn + sqrt2 * _get(flat, node + cols + 1),  # type: ignore[call-arg]
                    g, parent, lo, hi, heads, pool,
                    goal, gr, gc, diagonal, hmin, inv_delta, mask, cur,
                    free, used, n_open, g_goal, bound, pending,
                )  # fmt: skip
    if pending != -1:  # back into the pool, on top of its bucket, for the next round
        free, used = _push(heads, pool, cur & mask, pending, free, used)
    ints[_CUR] = cur
    ints[_USED] = used
    ints[_FREE] = free
    ints[_OPEN] = n_open
    ints[_EXPANDED] = expanded
    floats[_G_GOAL] = g_goal
    floats[_BOUND] = bound
    return done


@numba.njit(cache=True)
def _grown(a: np.ndarray, used: int) -> np.ndarray:
    """A copy of ``a`` with twice the room, its first ``used`` entries kept."""
    out = np.empty(a.shape[0] * 2, a.dtype)
    for i in range(used):
        out[i] = a[i]
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
    lo: np.ndarray,
    hi: np.ndarray,
    zero: bool,
) -> tuple[float, int]:
    """A* with f-buckets of width ``delta`` in a circular array of at least ``span`` buckets.

    ``span`` must exceed the largest f increase along one move divided by ``delta``, plus 2.
    ``g``, ``parent``, ``lo`` and ``hi`` are a :class:`Scratch`'s arrays, ``g`` all zero on
    entry; with ``zero`` the written part of ``g`` is zero again on return (without, the
    words it leaves may carry the :data:`CLOSED` bit).
    """
    cols = cost.shape[1]
    size = 1
    while size < span:  # a power of two: the bucket of a key is key & mask
        size *= 2
    heads = np.full(size, -1, np.int32)  # first pool slot of each bucket
    pool = np.empty(4096, np.int64)
    _store_g(g, start, 0.0)
    _mark(lo, hi, start // cols, start % cols)
    h0 = _h(start // cols, start % cols, goal // cols, goal % cols, diagonal, hmin)
    cur = np.int64(math.floor(h0 * (1.0 / delta)))
    pool[0] = start | (np.int64(-1) << 32)
    heads[cur & (size - 1)] = 0
    ints = np.array([cur, 1, -1, 1, 0], np.int64)
    floats = np.array([np.inf, np.inf])
    flat = cost.ravel()
    while not _bucket_rounds(flat, cost.shape[0], cols, start, goal, diagonal, hmin, delta,
                             size - 1, g, parent, lo, hi, heads, pool, ints, floats):
        pool = _grown(pool, ints[_USED])
    _clean(g, lo, hi, cost.shape[0], cols, zero)
    return floats[_G_GOAL], ints[_EXPANDED]


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
    lo: np.ndarray,
    hi: np.ndarray,
    zero: bool,
) -> tuple[float, int]:
    """A* with a binary heap on (f rounded down to ``quantum``, larger g first).

    The returned cost exceeds the optimum by less than ``quantum``. The scratch arrays are as
    for :func:`search_buckets`.
    """
    rows, cols = cost.shape
    flat = cost.ravel()
    gr = goal // cols
    gc = goal % cols
    sqrt2 = math.sqrt(2.0)
    inv_q = 1.0 / quantum
    off = DR * cols + DC
    w8 = np.empty(8, np.float64)

    hf = np.empty(1024, np.float64)
    hg = np.empty(1024, np.float64)
    hn = np.empty(1024, np.int32)
    _store_g(g, start, 0.0)
    _mark(lo, hi, start // cols, start % cols)
    hf[0] = math.floor(_h(start // cols, start % cols, gr, gc, diagonal, hmin) * inv_q)
    hg[0] = 0.0
    hn[0] = start
    size = 1
    expanded = 0
    g_goal = np.inf

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
        if g_top > _load_g(g, node):
            continue  # stale entry
        if node == goal:
            g_goal = g_top
            break
        expanded += 1
        r = node // cols
        c = node - r * cols
        _mark(lo, hi, r, c)
        nmoves = _move_costs(flat, node, r, c, rows, cols, diagonal, off, w8)
        for k in range(nmoves):
            if w8[k] == np.inf:
                continue  # blocked, or outside the grid (not to be read)
            ng_ = g_top + w8[k] if k < 4 else g_top + sqrt2 * w8[k]
            nb = node + off[k]
            if not ng_ < _load_g(g, nb) * KEEP:
                continue
            nr = r + DR[k]
            nc = c + DC[k]
            _store_g(g, nb, ng_)
            parent[nb] = k
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
    _clean(g, lo, hi, rows, cols, zero)
    return g_goal, expanded
