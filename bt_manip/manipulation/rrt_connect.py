"""Collision-free joint paths: bidirectional RRT-Connect, then shortcutting.

:func:`plan` grows one tree from the start and one from the goal (RRT-Connect: each round one
tree extends toward a random configuration and the other tries to connect to the new node all
the way), joins them and shortcuts the path. The trees take turns until one has outgrown the
other several times over: the smaller one is then trapped (a goal deep in a shelf, from which
few directions are free) and gets every round, half of them aimed near its own nodes, until it
catches up. Everything is deterministic: the random stream is
a ``numpy`` generator seeded by the caller (from the episode seed and the node's path), and the
budget is a count of collision checks (:attr:`PlanOptions.max_checks`), never wall time, so a
plan is the same on every machine. Segments are checked at :attr:`PlanOptions.step` rad per
joint at most.

A plan that cannot be made raises :class:`PlanError` whose message says why: the start or the
goal in collision (naming what touches), outside the joint limits, or no path within the budget
(with how far each tree grew), or stopped by the caller's ``stop`` callback (which a benchmark
uses to hold a wall-clock limit per problem; the planner itself never reads a clock).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Generator
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from bt_manip.manipulation.collision_scene import CollisionScene, named_contacts

# numpy's einsum without its Python wrapper, which costs more than the sums of a small tree
_einsum: Callable[..., np.ndarray] = getattr(
    getattr(getattr(np, "_core", None), "multiarray", None), "c_einsum", np.einsum)

__all__ = [
    "PlanError", "PlanOptions", "PlanResult", "check_end", "path_length", "plan", "plan_steps",
    "shortcut",
]


class PlanError(ValueError):
    """No collision-free path; the message says why."""


@dataclass(frozen=True)
class PlanOptions:
    """Budgets and resolutions of one plan (counts and radians, never seconds)."""

    step: float = 0.05
    """Largest joint move (rad) between two collision checks along a segment."""
    extend: float = 0.4
    """Largest joint-space distance (rad, Euclidean) a tree grows by in one extension."""
    max_checks: int = 200_000
    """Collision checks the search may spend before giving up."""
    shortcut_rounds: int = 20
    """Random shortcut attempts after a path is found (at most)."""
    shortcut_patience: int = 6
    """The random attempts end early once this many in a row have failed: the path is then
    near as short as the remaining attempts would make it, at a fraction of their checks."""
    goal_bias: float = 0.05
    """Share of samples that are the other tree's root."""
    balance: float = 3.0
    """A tree with more than this many times the other's nodes (and at least
    :attr:`balance_from` of them) waits while the smaller one extends: a tree trapped in a
    narrow region (a goal deep in a shelf) gets the samples instead of the tree that grows
    easily (0: the trees take turns whatever their sizes)."""
    balance_from: int = 100
    """Nodes the larger tree must have before :attr:`balance` applies (an easy problem's
    trees, smaller than this, take turns)."""
    trapped_share: float = 0.5
    """Share of a trapped tree's extensions (the smaller one while :attr:`balance` applies)
    aimed near one of its own nodes rather than anywhere: from a narrow pocket, a short step
    is far likelier to be free than one toward a far corner of the joint space."""
    trapped_spread: float = 0.2
    """Standard deviation (rad, per joint) of those nearby targets around the chosen node."""
    validate_step: float = 0.01
    """The found path is checked again at this resolution (rad per joint); a segment that
    clips an obstacle between the coarser checks is planned again at this resolution."""
    hulls_decide: bool = True
    """When neither end's convex hulls touch anything, a configuration whose hulls touch counts
    as blocked without asking the exact meshes (:meth:`CollisionScene.segment_free` with
    ``hulls_only``): every path found is then free for the meshes too, and the checks near
    obstacles cost a fraction. Ends whose hulls touch (a grasp in a tight spot) are planned
    with the meshes' answers."""


@dataclass(frozen=True)
class PlanResult:
    """A path from start to goal (every segment free at ``step``) and what it cost."""

    path: list[np.ndarray]
    samples: int
    checks: int
    nodes: tuple[int, int]
    """Nodes of the start and goal trees when they met."""


class _Tree:
    def __init__(self, root: np.ndarray, capacity: int) -> None:
        self.q = np.empty((capacity, root.size))
        self.parent = np.empty(capacity, dtype=np.int64)
        self.q[0] = root
        self.parent[0] = -1
        self.n = 1

    def add(self, q: np.ndarray, parent: int) -> int:
        if self.n == len(self.q):
            self.q = np.concatenate([self.q, np.empty_like(self.q)])
            self.parent = np.concatenate([self.parent, np.empty_like(self.parent)])
        self.q[self.n] = q
        self.parent[self.n] = parent
        self.n += 1
        return self.n - 1

    def nearest(self, q: np.ndarray) -> int:
        d = self.q[: self.n] - q
        return int(_einsum("ij,ij->i", d, d).argmin())

    def branch(self, index: int) -> list[np.ndarray]:
        out = []
        while index >= 0:
            out.append(self.q[index].copy())
            index = int(self.parent[index])
        return out


class _SegmentCheck(Protocol):
    def __call__(self, a: np.ndarray, b: np.ndarray, step: float) -> bool: ...


def _segment_check(scene: CollisionScene, hulls_only: bool) -> _SegmentCheck:
    """The segment test a plan uses: the scene's, on the hulls alone when ``hulls_only``."""
    if not hulls_only:
        return scene.segment_free

    def free(a: np.ndarray, b: np.ndarray, step: float) -> bool:
        return scene.segment_free(a, b, step, hulls_only=True)

    return free


def _hulls_decide(scene: CollisionScene, ends: tuple[np.ndarray, ...],
                  options: PlanOptions) -> bool:
    """Whether a plan between ``ends`` (free, checked) may count hull contacts as contacts:
    the option is on, the scene has a hull pass and no end's hulls touch."""
    if not options.hulls_decide or not isinstance(scene, CollisionScene) or scene.exact:
        return False
    return not any(scene.hulls_touch(q) for q in ends)


def _steer(a: np.ndarray, b: np.ndarray, extend: float) -> tuple[np.ndarray, bool]:
    """The point ``extend`` from ``a`` toward ``b`` (``b`` itself when nearer), and whether it
    is ``b``."""
    d = b - a
    dist = math.sqrt(float(d @ d))
    if dist <= extend:
        return b.copy(), True
    return a + d * (extend / dist), False


def check_end(scene: CollisionScene, q: np.ndarray, which: str) -> None:
    """PlanError when the path's ``which`` end (start, goal) is outside the joint limits
    (naming the joints) or in collision (naming what touches)."""
    if not scene.within_limits(q):
        bad = [scene.joint_names[i] for i in range(q.size)
               if not scene.lower[i] - 1e-9 <= q[i] <= scene.upper[i] + 1e-9]
        raise PlanError(f"the {which} is outside the joint limits of {', '.join(bad)}")
    if scene.collides(q):
        raise PlanError(f"the {which} is in collision: {named_contacts(scene.contacts(q))}")


def plan(
    scene: CollisionScene,
    start: np.ndarray,
    goal: np.ndarray,
    rng: np.random.Generator,
    options: PlanOptions = PlanOptions(),
    stop: Callable[[], bool] | None = None,
) -> PlanResult:
    """A collision-free path ``start`` -> ``goal`` (see the module docstring). ``stop``, when
    given, is asked once per sample and ends the search (PlanError) when it answers True."""
    steps = plan_steps(scene, start, goal, rng, options, stop)
    while True:
        try:
            next(steps)
        except StopIteration as done:
            result: PlanResult = done.value
            return result


def plan_steps(
    scene: CollisionScene,
    start: np.ndarray,
    goal: np.ndarray,
    rng: np.random.Generator,
    options: PlanOptions = PlanOptions(),
    stop: Callable[[], bool] | None = None,
) -> Generator[int, None, PlanResult]:
    """:func:`plan` in rounds: yields the checks spent so far after every round of the search
    (one extension and one connection: at most ``2 * extend / step`` segment checks and a
    connection's), returns the :class:`PlanResult` (raises :class:`PlanError`). A caller that
    advances it once per tick bounds each tick's work by a count of checks."""
    start = np.asarray(start, dtype=float)
    goal = np.asarray(goal, dtype=float)
    first = scene.checks
    check_end(scene, start, "start")
    check_end(scene, goal, "goal")
    hulls_only = _hulls_decide(scene, (start, goal), options)
    free = _segment_check(scene, hulls_only)
    if free(start, goal, options.step):
        # checked again at the validation step, as every path is
        direct = _validated(scene, [start, goal], rng, options, first, stop, hulls_only)
        return PlanResult(direct, 0, scene.checks - first, (1, 1))
    lo = np.where(np.isfinite(scene.lower), scene.lower, -math.pi)
    hi = np.where(np.isfinite(scene.upper), scene.upper, math.pi)
    trees = (_Tree(start, 1024), _Tree(goal, 1024))
    draws = _Draws(rng, lo, hi)
    samples = 0
    a, b = 0, 1
    while scene.checks - first < options.max_checks:
        if stop is not None and stop():
            raise PlanError(f"stopped after {samples} samples ({scene.checks - first} collision "
                            f"checks; trees of {trees[0].n} and {trees[1].n} nodes)")
        samples += 1
        a, b, trapped = _turn(trees, a, b, options)
        if draws.coin() < options.goal_bias:
            target = trees[b].q[0].copy()
        elif trapped and draws.coin() < options.trapped_share:
            near = trees[a].q[min(int(draws.coin() * trees[a].n), trees[a].n - 1)]
            target = np.clip(near + options.trapped_spread * draws.normal(), lo, hi)
        else:
            target = draws.config()
        grown = _extend(free, trees[a], target, options)
        if grown is not None:
            met = _connect(free, trees[b], trees[a].q[grown], options)
            if met is not None:
                one, other = trees[a].branch(grown), trees[b].branch(met)
                path = one[::-1] + other if a == 0 else other[::-1] + one
                path = _dedupe(path)
                path = shortcut(scene, path, rng, options, hulls_only)
                path = _validated(scene, path, rng, options, first, stop, hulls_only)
                return PlanResult(path, samples, scene.checks - first,
                                  (trees[0].n, trees[1].n))
        a, b = b, a
        yield scene.checks - first
    raise PlanError(
        f"no path within {options.max_checks} collision checks ({samples} samples; the start "
        f"tree grew to {trees[0].n} nodes, the goal tree to {trees[1].n})"
    )


class _Block:
    """Values drawn ``BLOCK`` at a time by ``draw`` and handed out one by one, in order."""

    def __init__(self, draw: Callable[[], np.ndarray]) -> None:
        self._draw = draw
        self._rows: np.ndarray = np.empty(0)
        self._next = 0

    def take(self) -> np.ndarray:
        if self._next == len(self._rows):
            self._rows, self._next = self._draw(), 0
        self._next += 1
        row: np.ndarray = self._rows[self._next - 1]
        return row


class _Draws:
    """The search's random numbers, drawn from the generator in blocks of :data:`BLOCK` (one
    draw of a block costs about what one configuration's did): coin flips in [0, 1),
    configurations uniform within the limits and standard normal steps, each kind in the
    order asked."""

    BLOCK = 128

    def __init__(self, rng: np.random.Generator, lo: np.ndarray, hi: np.ndarray) -> None:
        shape, span = (self.BLOCK, lo.size), hi - lo
        self._coins = _Block(lambda: rng.random(self.BLOCK))
        self._configs = _Block(lambda: lo + span * rng.random(shape))
        self._normals = _Block(lambda: rng.standard_normal(shape))

    def coin(self) -> float:
        return float(self._coins.take())

    def config(self) -> np.ndarray:
        return self._configs.take()

    def normal(self) -> np.ndarray:
        return self._normals.take()


def _turn(trees: tuple[_Tree, _Tree], a: int, b: int,
          options: PlanOptions) -> tuple[int, int, bool]:
    """Which tree extends this round and which connects, and whether the extending one is
    trapped: the smaller one when the other outgrew it (:attr:`PlanOptions.balance`), else the
    one whose turn it is."""
    small, large = (0, 1) if trees[0].n < trees[1].n else (1, 0)
    n = trees[large].n
    if options.balance and n >= options.balance_from and trees[small].n * options.balance < n:
        return small, large, True
    return a, b, False


def _validated(
    scene: CollisionScene, path: list[np.ndarray], rng: np.random.Generator,
    options: PlanOptions, first: int, stop: Callable[[], bool] | None = None,
    hulls_only: bool = False,
) -> list[np.ndarray]:
    """``path`` with every segment free at ``validate_step`` (on the hulls alone when
    ``hulls_only``): a segment that is not is planned again at that resolution (within what is
    left of the budget)."""
    if options.validate_step >= options.step:
        return path
    free = _segment_check(scene, hulls_only)
    out = [path[0]]
    i = 0
    while i < len(path) - 1:
        a, b = path[i], path[i + 1]
        if free(a, b, options.validate_step):
            out.append(b)
            i += 1
            continue
        # plan again, finely, to the next waypoint that is itself free (the goal is)
        j = i + 1
        while j < len(path) - 1 and scene.collides(path[j]):
            j += 1
        left = options.max_checks - (scene.checks - first)
        fine = dataclasses.replace(options, step=options.validate_step, max_checks=max(left, 1))
        out += plan(scene, a, path[j], rng, fine, stop).path[1:]
        i = j
    return out


def _extend(
    free: _SegmentCheck, tree: _Tree, target: np.ndarray, options: PlanOptions
) -> int | None:
    near = tree.nearest(target)
    q, _ = _steer(tree.q[near], target, options.extend)
    if free(tree.q[near], q, options.step):
        return tree.add(q, near)
    return None


def _connect(
    free: _SegmentCheck, tree: _Tree, target: np.ndarray, options: PlanOptions
) -> int | None:
    """Grow ``tree`` toward ``target`` until it reaches it (its index) or is blocked (None)."""
    near = tree.nearest(target)
    while True:
        q, reached = _steer(tree.q[near], target, options.extend)
        if not free(tree.q[near], q, options.step):
            return None
        near = tree.add(q, near)
        if reached:
            return near


def _dedupe(path: list[np.ndarray]) -> list[np.ndarray]:
    out = [path[0]]
    for q in path[1:]:
        if not np.array_equal(q, out[-1]):
            out.append(q)
    return out


def path_length(path: list[np.ndarray]) -> float:
    """Sum of the Euclidean joint-space lengths of the segments (rad)."""
    return float(sum(np.linalg.norm(b - a) for a, b in itertools.pairwise(path)))


def shortcut(
    scene: CollisionScene, path: list[np.ndarray], rng: np.random.Generator,
    options: PlanOptions = PlanOptions(), hulls_only: bool = False,
) -> list[np.ndarray]:
    """``path`` with waypoints skipped where the straight segment between them is free (on the
    hulls alone when ``hulls_only``): first greedily from the start, then
    ``options.shortcut_rounds`` random pairs of points on it."""
    free = _segment_check(scene, hulls_only)
    path = _greedy(free, path, options.step)
    failed = 0
    along = _along(path)
    for _ in range(options.shortcut_rounds):
        if len(path) < 3 or failed >= options.shortcut_patience or along[-1] <= 0.0:
            break
        s, t = sorted(rng.uniform(0.0, along[-1], 2))
        (i, qa), (j, qb) = _point_at(path, along, s), _point_at(path, along, t)
        failed += 1
        if j <= i:
            continue
        # qa and qb lie between the configurations their segments were checked at, and the
        # pieces of those segments left in the path are checked at other configurations than
        # the whole was: check the pieces too, so that every segment of the result is free at
        # ``step`` as checked on its own (as a validator checks it)
        if (free(qa, qb, options.step) and free(path[i], qa, options.step)
                and free(qb, path[j + 1], options.step)):
            path = [*path[:i + 1], qa, qb, *path[j + 1:]]
            path = _dedupe(path)
            along = _along(path)
            failed = 0
    return path


def _greedy(free: _SegmentCheck, path: list[np.ndarray], step: float) -> list[np.ndarray]:
    out = [path[0]]
    i = 0
    while i < len(path) - 1:
        j = len(path) - 1
        while j > i + 1 and not free(path[i], path[j], step):
            j -= 1
        out.append(path[j])
        i = j
    return out


def _along(path: list[np.ndarray]) -> np.ndarray:
    """How far along ``path`` (rad, Euclidean) each waypoint lies: 0 for the first."""
    steps = np.diff(np.asarray(path, dtype=float), axis=0)
    return np.concatenate([[0.0], np.cumsum(np.sqrt(np.einsum("ij,ij->i", steps, steps)))])


def _point_at(path: list[np.ndarray], along: np.ndarray, s: float) -> tuple[int, np.ndarray]:
    """The point ``s`` rad along ``path`` (``along``: :func:`_along` of it) and the index of
    the segment's first waypoint."""
    i = min(int(np.searchsorted(along[1:], s)), len(path) - 2)
    a, b = path[i], path[i + 1]
    length = float(along[i + 1] - along[i])
    return i, a + (b - a) * (min(max(s - float(along[i]), 0.0), length) / max(length, 1e-12))
