"""The compiled kernels of the pose search of :mod:`bt_manip.navigation.lattice`.

Compiled with numba, ``cache=True`` (the machine code is stored next to the module and loaded
by later processes): the search over poses (:func:`search_poses`), its moves and footprint
checks (:func:`pose_fits`), its binary heap, and the goal's obstacle-aware distance field that
the heuristic reads (:class:`GoalField`, computed only as far as the search asks). The options,
the checks of start and goal and the result (:class:`~bt_manip.navigation.lattice.PosePlan`)
are the API's, in :mod:`bt_manip.navigation.lattice`.

Arrays are copied by loops, never by assigning one array to a slice of another: numba checks
such an assignment's shapes and compiles, for its error message, its string formatting (join,
str of integers), seconds on the first run after an install, for a copy LLVM emits the same
either way.
"""

from __future__ import annotations

import math
import mmap

import numba
import numpy as np

from bt_manip.navigation.outline_check import _clearance_value, _groups_free, _points_free


@numba.njit(cache=True, inline="always")
def _heap_push(keys: np.ndarray, vals: np.ndarray, size: int, key: float, val: int) -> int:
    """Add (key, val) to the binary min-heap in ``keys``/``vals``; returns the new size."""
    j = size
    while j > 0:
        p = (j - 1) >> 1
        if keys[p] <= key:
            break
        keys[j] = keys[p]
        vals[j] = vals[p]
        j = p
    keys[j] = key
    vals[j] = val
    return size + 1


@numba.njit(cache=True, inline="always")
def _heap_pop(keys: np.ndarray, vals: np.ndarray, size: int) -> tuple[float, int, int]:
    """Remove the smallest entry of the heap; returns (key, val, new size)."""
    key = keys[0]
    val = vals[0]
    size -= 1
    last_key = keys[size]
    last_val = vals[size]
    i = 0
    while True:  # sift the last entry down from the root
        ch = 2 * i + 1
        if ch >= size:
            break
        if ch + 1 < size and keys[ch + 1] < keys[ch]:
            ch += 1
        if keys[ch] >= last_key:
            break
        keys[i] = keys[ch]
        vals[i] = vals[ch]
        i = ch
    keys[i] = last_key
    vals[i] = last_val
    return key, val, size


@numba.njit(cache=True)
def _grown(a: np.ndarray, n: int) -> np.ndarray:
    """A copy of the 1-D array ``a`` with room for ``n`` entries (the new ones uninitialised)."""
    out = np.empty(n, a.dtype)
    for i in range(a.shape[0]):  # a loop: see the module's docstring
        out[i] = a[i]
    return out


@numba.njit(cache=True)
def _grown_rows(a: np.ndarray, n: int) -> np.ndarray:
    """A copy of the 2-D array ``a`` with room for ``n`` rows (the new ones uninitialised)."""
    out = np.empty((n, a.shape[1]), a.dtype)
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            out[i, j] = a[i, j]
    return out


# Neighbour order of the goal field: four sides, then the four diagonals.
DR8 = np.array([-1, 1, 0, 0, -1, -1, 1, 1], np.int64)
DC8 = np.array([0, 0, -1, 1, -1, 1, -1, 1], np.int64)


@numba.njit(cache=True, inline="always")
def _known(dist: np.ndarray, row: int, col: int, goal: int) -> float:
    """The distance of a cell found so far (``inf`` if not reached: 0 stands for that, except
    at the goal)."""
    d = dist[row, col]
    if d == 0.0 and row * dist.shape[1] + col != goal:
        return np.inf
    return d  # type: ignore[no-any-return]  # numba body: dist items are floats


@numba.njit(cache=True, inline="always")
def _final(dist: np.ndarray, row: int, col: int, goal: int, front: float) -> bool:
    """Whether the cell's distance is final: reached, and not beyond the frontier."""
    return _known(dist, row, col, goal) <= front


@numba.njit(cache=True)
def _settle(
    free: np.ndarray,
    dist: np.ndarray,
    heap_d: np.ndarray,
    heap_i: np.ndarray,
    state: np.ndarray,
    frontier: np.ndarray,
    row: int,
    col: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Run the goal's Dijkstra search on ``free`` cells until cell (row, col) has its final
    distance, or until the search is over (``row`` -1 runs it to the end).

    ``dist`` holds the distances so far (cells, 8-connected, no corner cutting; 0 where not
    reached, except at the goal cell ``state[1]``), ``heap_d``/``heap_i`` the open list and
    ``state[0]`` its size,
    ``frontier[0]`` the last distance taken from it: every distance up to the frontier is
    final, since later entries only add to larger ones. Pausing leaves the order of the work
    unchanged, so the distances are those of one search run to the end. Returns the open list
    (grown if it had to be)."""
    rows, cols = free.shape
    limit = rows * cols * 4 + 8  # most entries the open list may hold
    size = state[0]
    goal = state[1]
    front = frontier[0]
    sq2 = math.sqrt(2.0)
    while size > 0 and (row < 0 or not _final(dist, row, col, goal, front)):
        d, node, size = _heap_pop(heap_d, heap_i, size)
        front = d
        r = node // cols
        c = node % cols
        if d > dist[r, c]:
            continue
        for k in range(8):
            nr = r + DR8[k]
            nc = c + DC8[k]
            if nr < 0 or nr >= rows or nc < 0 or nc >= cols or not free[nr, nc]:
                continue
            if k >= 4 and not (free[nr, c] and free[r, nc]):
                continue
            nd = d + (sq2 if k >= 4 else 1.0)
            if nd < _known(dist, nr, nc, goal) and size < limit:
                dist[nr, nc] = nd
                if size == heap_d.shape[0]:  # grow the open list (it starts small)
                    heap_d = _grown(heap_d, min(limit, 2 * size))
                    heap_i = _grown(heap_i, heap_d.shape[0])
                size = _heap_push(heap_d, heap_i, size, nd, nr * cols + nc)
    state[0] = size
    frontier[0] = front
    return heap_d, heap_i


class GoalField:
    """The goal's distance field, computed as far as the pose search asks (see
    :func:`_settle`)."""

    def __init__(self, free: np.ndarray, goal: tuple[int, int] | None) -> None:
        self.free = free
        # zeros from an anonymous map: pages become resident only where the search writes
        size = max(1, free.size)
        self.dist = np.frombuffer(mmap.mmap(-1, size * 8), np.float64)[: free.size]
        self.dist = self.dist.reshape(free.shape)
        self.heap_d = np.empty(1 << 12)
        self.heap_i = np.empty(1 << 12, np.int64)
        self.state = np.array([0, -1], np.int64)
        self.frontier = np.full(1, -1.0)
        if goal is not None and free[goal]:
            self.heap_d[0] = 0.0
            self.heap_i[0] = self.state[1] = goal[0] * free.shape[1] + goal[1]
            self.state[0] = 1

    def whole(self) -> np.ndarray:
        """The distance of every cell, ``inf`` where unreachable (the search run to the end)."""
        self.heap_d, self.heap_i = _settle(
            self.free, self.dist, self.heap_d, self.heap_i, self.state, self.frontier, -1, -1
        )
        out = np.where(self.dist == 0.0, np.inf, self.dist)
        if self.state[1] >= 0:
            out.reshape(-1)[self.state[1]] = 0.0
        return out


@numba.njit(cache=True)
def _heuristic(
    x: float,
    y: float,
    x0: float,
    y0: float,
    res: float,
    goal: np.ndarray,
    free: np.ndarray,
    dist: np.ndarray,
    heap_d: np.ndarray,
    heap_i: np.ndarray,
    state: np.ndarray,
    frontier: np.ndarray,
) -> tuple[float, np.ndarray, np.ndarray]:
    """Obstacle-aware distance (m) from (x, y) to the goal, and the open list of the field."""
    rows, cols = dist.shape
    col = math.floor((x - x0) / res)
    row = math.floor((y - y0) / res)
    if row < 0 or row >= rows or col < 0 or col >= cols:
        return np.inf, heap_d, heap_i
    heap_d, heap_i = _settle(free, dist, heap_d, heap_i, state, frontier, row, col)
    d = _known(dist, row, col, state[1])
    h = d * res if d < np.inf else math.hypot(x - goal[0], y - goal[1]) + 5.0
    return h, heap_d, heap_i


@numba.njit(cache=True)
def pose_fits(
    clear: np.ndarray,
    clear_high: np.ndarray,
    x0: float,
    y0: float,
    res: float,
    pts: np.ndarray,
    pts_high: np.ndarray,
    x: float,
    y: float,
    th: float,
    need: float,
) -> bool:
    """Footprint points clear of everything, carried-object points clear of tall obstacles."""
    return _points_free(clear, x0, y0, res, pts, x, y, th, need) and _points_free(
        clear_high, x0, y0, res, pts_high, x, y, th, need
    )


@numba.njit(cache=True)
def _points_margin(
    clear: np.ndarray,
    x0: float,
    y0: float,
    res: float,
    pts: np.ndarray,
    x: float,
    y: float,
    th: float,
) -> float:
    """The smallest clearance (m) of the cells under the points (``-inf`` off the grid)."""
    rows, cols = clear.shape
    c = math.cos(th)
    s = math.sin(th)
    low = np.inf
    for k in range(pts.shape[0]):
        px = x + c * pts[k, 0] - s * pts[k, 1]
        py = y + s * pts[k, 0] + c * pts[k, 1]
        col = math.floor((px - x0) / res)
        row = math.floor((py - y0) / res)
        if row < 0 or row >= rows or col < 0 or col >= cols:
            return -np.inf
        low = min(low, _clearance_value(clear[row, col], res))
    return low  # type: ignore[no-any-return]  # numba body: a float


@numba.njit(cache=True)
def _pose_margin(
    clear: np.ndarray,
    clear_high: np.ndarray,
    x0: float,
    y0: float,
    res: float,
    pts: np.ndarray,
    pts_high: np.ndarray,
    x: float,
    y: float,
    th: float,
) -> float:
    """The smallest clearance of the footprint and the carried-object points (m)."""
    return min(
        _points_margin(clear, x0, y0, res, pts, x, y, th),
        _points_margin(clear_high, x0, y0, res, pts_high, x, y, th),
    )


@numba.njit(cache=True)
def _move(
    x: float, y: float, th: float, kind: int, curv: float, length: float, pivot: float, t: float
) -> tuple[float, float, float]:
    """Pose after the fraction ``t`` of a move (kind 0/1 drive with curvature, 2 turn)."""
    if kind == 2:  # turn on the spot about the pivot by ``length`` rad
        px = x + pivot * math.cos(th)
        py = y + pivot * math.sin(th)
        nth = th + t * length
        return px - pivot * math.cos(nth), py - pivot * math.sin(nth), nth
    d = t * length * (1.0 if kind == 0 else -1.0)
    if abs(curv) < 1e-9:
        return x + d * math.cos(th), y + d * math.sin(th), th
    nth = th + d * curv
    return (
        x + (math.sin(nth) - math.sin(th)) / curv,
        y - (math.cos(nth) - math.cos(th)) / curv,
        nth,
    )


@numba.njit(cache=True)
def search_poses(
    clear: np.ndarray,
    clear_high: np.ndarray,
    x0: float,
    y0: float,
    res: float,
    pts: np.ndarray,
    pts_high: np.ndarray,
    reach: float,
    need: float,
    groups: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float],
    groups_high: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float],
    windows: tuple[np.ndarray, np.ndarray, int],
    windows_high: tuple[np.ndarray, np.ndarray, int],
    free: np.ndarray,
    dist: np.ndarray,
    heap_d: np.ndarray,
    heap_i: np.ndarray,
    state: np.ndarray,
    frontier: np.ndarray,
    start: np.ndarray,
    goal: np.ndarray,
    params: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, int]:
    step = params[0]
    curv = params[1]
    nh = int(params[2])
    xyb = params[3]
    tstep = params[4]
    tcost = params[5]
    rev = params[6]
    gxy = params[7]
    gyaw = params[8]
    maxexp = int(params[9])
    spacing = params[10]
    pivot = params[11]
    need_low = params[12]
    tight_radius = params[13]
    steer_cost = params[14]
    gp, gfirst, gcentre, gradius, greach = groups
    hp, hfirst, hcentre, hradius, hreach = groups_high
    glow, gdone, gwin = windows
    hlow, hdone, hwin = windows_high
    # a start closer to obstacles than ``need`` (but not touching them): within
    # ``tight_radius`` of it, moves need only keep ``need_low``, at three times the cost from a
    # pose without the full margin, so the plan gets out of the tight spot at once
    start_tight = not pose_fits(
        clear, clear_high, x0, y0, res, pts, pts_high, start[0], start[1], start[2], need
    )
    cols = clear.shape[1]
    bx = math.ceil(cols * res / xyb) + 1
    # States are stored in the order they are first reached (slots), found by their bin key:
    # memory grows with the search, not with the number of bins of a large map.
    slot_of = numba.typed.Dict.empty(key_type=numba.types.int64, value_type=numba.types.int64)
    room = 1 << 12
    best = np.empty(room)
    closed = np.zeros(room, np.bool_)
    parent = np.empty(room, np.int64)
    move_of = np.empty(room, np.int64)
    pose = np.empty((room, 3))
    used = 0
    cap = 1 << 16
    hf = np.empty(cap)
    hi = np.empty(cap, np.int64)
    size = 0
    two_pi = 2.0 * math.pi

    def key(x: float, y: float, th: float) -> int:
        ix = math.floor((x - x0) / xyb)
        iy = math.floor((y - y0) / xyb)
        ih = math.floor(((th % two_pi) / two_pi) * nh + 0.5) % nh
        return (iy * bx + ix) * nh + ih  # type: ignore[no-any-return]  # numba body: integer arithmetic

    k0 = 0
    slot_of[key(start[0], start[1], start[2])] = k0
    used = 1
    best[k0] = 0.0
    parent[k0] = -1
    move_of[k0] = -1
    pose[k0, 0] = start[0]
    pose[k0, 1] = start[1]
    pose[k0, 2] = start[2]
    hf[0], heap_d, heap_i = _heuristic(
        start[0], start[1], x0, y0, res, goal, free, dist, heap_d, heap_i, state, frontier
    )
    hi[0] = k0
    size = 1
    expanded = 0
    # moves: (kind, curvature, length)
    kinds = np.array([0, 0, 0, 1, 1, 1, 2, 2])
    curvs = np.array([0.0, curv, -curv, 0.0, curv, -curv, 0.0, 0.0])
    lens = np.array([step, step, step, step, step, step, tstep, -tstep])
    costs = np.array(
        [
            step,
            step * 1.05,
            step * 1.05,
            rev * step,
            rev * step * 1.05,
            rev * step * 1.05,
            tcost * tstep,
            tcost * tstep,
        ]
    )
    while size > 0:
        f, k, size = _heap_pop(hf, hi, size)
        x = pose[k, 0]
        y = pose[k, 1]
        th = pose[k, 2]
        g = best[k]
        h, heap_d, heap_i = _heuristic(
            x, y, x0, y0, res, goal, free, dist, heap_d, heap_i, state, frontier
        )
        if closed[k] or f > g + h + 1e-9:
            continue  # expanded already, or stale
        dyaw = (th - goal[2] + math.pi) % two_pi - math.pi
        if math.hypot(x - goal[0], y - goal[1]) <= gxy and abs(dyaw) <= gyaw:
            return parent, move_of, pose, k, expanded
        expanded += 1
        if expanded > maxexp:
            break
        closed[k] = True
        near_start = start_tight and math.hypot(x - start[0], y - start[1]) <= tight_radius
        tight = near_start and (
            _pose_margin(clear, clear_high, x0, y0, res, pts, pts_high, x, y, th) < need
        )
        for m in range(8):
            kind = kinds[m]
            length = lens[m]
            travel = abs(length) * (reach if kind == 2 else 1.0) + (
                reach * abs(length * curvs[m]) if kind != 2 else 0.0
            )
            nsub = max(1, math.ceil(travel / spacing))
            ok = True
            nx = x
            ny = y
            nt = th
            keep = need_low if tight else need
            for j in range(1, nsub + 1):
                nx, ny, nt = _move(x, y, th, kind, curvs[m], length, pivot, j / nsub)
                # pose_fits of the same points, grouped (the same answer, fewer looks)
                cn = math.cos(nt)
                sn = math.sin(nt)
                if not (
                    _groups_free(
                        clear, x0, y0, res, gp, gfirst, gcentre, gradius, greach, glow, gdone,
                        gwin, nx, ny, cn, sn, keep,
                    )
                    and _groups_free(
                        clear_high, x0, y0, res, hp, hfirst, hcentre, hradius, hreach, hlow,
                        hdone, hwin, nx, ny, cn, sn, keep,
                    )
                ):
                    ok = False
                    break
            if not ok:
                continue
            bin_key = key(nx, ny, nt)
            ng = g + costs[m] * (3.0 if tight else 1.0)
            prev = move_of[k]
            if prev >= 0 and (kinds[prev] != kind or curvs[prev] != curvs[m]):
                ng += steer_cost
            nk = np.int64(-1)
            if bin_key in slot_of:
                nk = slot_of[bin_key]
                # an expanded pose keeps its place: its successors were reached from it
                if closed[nk] or ng >= best[nk]:
                    continue
            else:
                if used == best.shape[0]:
                    best = _grown(best, 2 * used)
                    closed = _grown(closed, 2 * used)
                    closed[used:] = False
                    parent = _grown(parent, 2 * used)
                    move_of = _grown(move_of, 2 * used)
                    pose = _grown_rows(pose, 2 * used)
                nk = used  # type: ignore[assignment]  # numba body: numba unifies int64 and int
                used += 1
                slot_of[bin_key] = nk
            best[nk] = ng
            parent[nk] = k
            move_of[nk] = m
            pose[nk, 0] = nx
            pose[nk, 1] = ny
            pose[nk, 2] = nt
            if size == hf.shape[0]:
                nhf = np.empty(size * 2)
                nhi = np.empty(size * 2, np.int64)
                for i in range(size):
                    nhf[i] = hf[i]
                    nhi[i] = hi[i]
                hf = nhf
                hi = nhi
            h, heap_d, heap_i = _heuristic(
                nx, ny, x0, y0, res, goal, free, dist, heap_d, heap_i, state, frontier
            )
            nf = ng + h
            size = _heap_push(hf, hi, size, nf, nk)  # type: ignore[arg-type]  # numba body: int64 is numba's int
    return parent, move_of, pose, -1, expanded
