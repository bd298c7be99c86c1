"""Seeded fault injection: make runs fail on purpose to prove that trees recover.

Specifications (``--inject``, repeatable):

``NAME:failure:P``  the node whose name or node ID is NAME fails with probability P each time it
                    starts (a fresh execution, not every tick of a RUNNING node), without
                    running; its reason says the failure was injected.
``slip:P``          an object held in a gripper slips out (its grasp is released) with
                    probability P per carry; robot behaviours that carry ask :func:`plan_slip`
                    when they start and call :func:`slip_out` when the slip is due.
``block:P``         with probability P per navigation, an obstacle is dropped on the planned
                    route: the Navigate behaviour calls :func:`block_route` (the crate falls
                    as the navigation starts); Nav2's planners draw it with :func:`plan_block`
                    and keep it with :meth:`FaultInjector.defer_block`, and FollowPath drops
                    it when the robot comes within :data:`BLOCK_NEAR` of its place (an obstacle
                    appearing in front of the robot, the case Nav2's recoveries are for).
``odom_noise:K[:K_ROT]``
                    (localisation only) the wheel odometry errs: K m of travel error after 1 m
                    travelled (its variance grows with the distance), K_ROT rad of heading error
                    per radian turned (default K) and K rad per metre travelled.
``lidar_noise:SIGMA``
                    (localisation only) the laser's ranges get Gaussian noise of SIGMA m.
``lidar_dropout:P`` (localisation only) each beam of each scan is lost with probability P.
``kidnap:T``        (localisation only) at sim time T the robot, with what it holds, is
                    carried 0.5-1.5 m and turned up to 0.5 rad to a free pose, and its
                    localisation is not told (:mod:`bt_manip.localization.runtime`).
``pose_noise:SIGMA_M[:SIGMA_DEG]``
                    the pose the robot perceives of each object is off by an offset drawn once
                    per object and episode: x and y normal with sigma SIGMA_M (m), yaw normal
                    with sigma SIGMA_DEG (deg, default 2). Nodes that plan from an object's pose
                    read it through
                    :func:`bt_manip.manipulation.perception.perceived_pose`; checks and
                    physics keep the ground truth.

This module is the whole fault layer. Node failures are wrapped around the targeted nodes when
the tree is loaded (:func:`inject_node_failures`), invisibly: the tree's nodes, their order,
names, IDs, exported XML and report paths are those of the tree without faults. World faults act
on the World (a grasp released, a crate spawned).

Every draw comes from one generator seeded by the episode seed, so a run with faults is as
repeatable as one without. What was injected is kept in :attr:`FaultInjector.events` for the
run report.
"""

from __future__ import annotations

import difflib
import math
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from bt_manip.bt.status import NodeStatus
from bt_manip.clock import Clock
from bt_manip.errors import InputError, Problem
from bt_manip.sim.world_spec import COLOURS, BodySpec, Part, Pose3D, Range2D

if TYPE_CHECKING:
    from bt_manip.bt.node import BtNode
    from bt_manip.bt.tree import Tree
    from bt_manip.sim.robot import Robot
    from bt_manip.sim.world import World

WORLD_FAULTS = ("slip", "block")
POSE_NOISE = "pose_noise"
ODOM_NOISE = "odom_noise"
LIDAR_NOISE = "lidar_noise"
LIDAR_DROPOUT = "lidar_dropout"
KIDNAP = "kidnap"
LOCALIZATION_FAULTS = (ODOM_NOISE, LIDAR_NOISE, LIDAR_DROPOUT, KIDNAP)
"""Faults of a robot's sensors and belief: they need localisation (``--localize``)."""
EXPECTED = ("expected NAME:failure:P, slip:P, block:P or pose_noise:SIGMA_M[:SIGMA_DEG] (with "
            "--localize also odom_noise:K[:K_ROT], lidar_noise:SIGMA, lidar_dropout:P or "
            "kidnap:T)")
MAX_LIDAR_SIGMA = 1.0
"""Largest range noise (m) of ``lidar_noise``."""
MAX_KIDNAP_TIME = 86_400.0
"""Latest sim time (s) a ``kidnap`` may be due at."""
MAX_SIGMA_M = 0.5
"""Largest position sigma (m) of ``pose_noise``: beyond, the object is not where it was seen."""
MAX_SIGMA_DEG = 90.0
"""Largest yaw sigma (deg) of ``pose_noise``."""
DEFAULT_SIGMA_DEG = 2.0
"""Yaw sigma (deg) of ``pose_noise`` when only the position sigma is given."""
INJECTED_REASON = "injected failure (--inject)"
"""The reason a node gives when an injected failure stops it."""

SLIP_AFTER = 0.5
"""Sim seconds into a carrying move at which an injected slip happens."""
BLOCK_SIZE = 0.3
"""Side (m) of the crate an injected ``block`` fault drops on the route."""
BLOCK_CLEARANCE = 1.5
"""The crate falls at least this far (m) from the route's start and its goal."""
BLOCK_NEAR = 1.0
"""A deferred crate (Nav2's FollowPath) falls when the robot comes this close (m) to its place."""
CRATE_DROP_HEIGHT = 0.3
"""Height (m) of the crate's underside above the floor when it appears: it falls into place."""
CRATE_MASS = 8.0
"""Mass (kg) of the dropped crate: heavy enough to stay where it falls."""
CRATE_FRICTION = 0.9
"""Friction coefficient of the dropped crate."""


@dataclass(frozen=True)
class FaultSpec:
    """One ``--inject`` argument."""

    kind: str  # "failure" | "slip" | "block" | "pose_noise"
    probability: float
    target: str = ""  # node name or ID, for "failure"
    sigma_m: float = 0.0
    """Position sigma (m), for "pose_noise"."""
    sigma_deg: float = 0.0
    """Yaw sigma (deg), for "pose_noise"."""
    values: tuple[float, ...] = ()
    """The numbers of a localisation fault: (K, K_ROT) for "odom_noise", (SIGMA,) for
    "lidar_noise", (P,) for "lidar_dropout", (T,) for "kidnap"."""

    def text(self) -> str:
        if self.kind == "failure":
            return f"{self.target}:failure:{self.probability:g}"
        if self.kind == POSE_NOISE:
            return f"{POSE_NOISE}:{self.sigma_m:g}:{self.sigma_deg:g}"
        if self.kind in LOCALIZATION_FAULTS:
            return ":".join([self.kind, *(f"{v:g}" for v in self.values)])
        return f"{self.kind}:{self.probability:g}"


def parse_fault(text: str) -> FaultSpec:
    """Read ``NAME:failure:P``, ``slip:P``, ``block:P`` or ``pose_noise:SIGMA_M[:SIGMA_DEG]``;
    InputError when malformed."""
    parts = text.split(":")

    def bad(why: str) -> InputError:
        return InputError([Problem("--inject", None, f"'{text}': {why}; {EXPECTED}")])

    if parts[0] == POSE_NOISE:
        return _parse_pose_noise(parts[1:], bad)
    if parts[0] in LOCALIZATION_FAULTS:
        return _parse_localization_fault(parts[0], parts[1:], bad)
    if len(parts) == 2 and parts[0] in WORLD_FAULTS:
        kind, target, p_text = parts[0], "", parts[1]
    elif len(parts) == 3 and parts[1] == "failure" and parts[0]:
        kind, target, p_text = "failure", parts[0], parts[2]
    elif len(parts) == 3 and parts[0]:
        raise bad(f"unknown fault kind '{parts[1]}'{_close(parts[1], ['failure'])}")
    elif len(parts) == 2 and parts[0]:
        hint = (_close(parts[0], [*WORLD_FAULTS, POSE_NOISE])
                or _close(parts[0], list(LOCALIZATION_FAULTS)))
        if not hint:
            hint = f" (for a node, write {parts[0]}:failure:{parts[1]})"
        raise bad(f"unknown fault kind '{parts[0]}'{hint}")
    else:
        raise bad("not a fault specification")
    try:
        p = float(p_text)
    except ValueError:
        raise bad(f"probability '{p_text}' is not a number") from None
    if not 0.0 <= p <= 1.0:
        raise bad(f"probability {p} is not within 0..1")
    return FaultSpec(kind, p, target)


def _bounded(text: str, name: str, top: float, bad: Callable[[str], InputError],
             unit: str = "") -> float:
    """``text`` as a number within 0..``top`` (``unit`` for the message), else ``bad``."""
    try:
        value = float(text)
    except ValueError:
        raise bad(f"{name} '{text}' is not a number") from None
    if not 0.0 <= value <= top:  # also refuses nan
        unit = f" {unit}" if unit else ""
        raise bad(f"{name} {text}{unit} is not within 0..{top:g}{unit}")
    return value


def _parse_pose_noise(values: list[str], bad: Callable[[str], InputError]) -> FaultSpec:
    """The sigmas of ``pose_noise:SIGMA_M[:SIGMA_DEG]`` (``values`` after the kind)."""
    if len(values) not in (1, 2):
        raise bad("pose_noise takes a position sigma in metres and optionally a yaw sigma in deg")
    sigmas = [
        _bounded(v, "sigma", top, bad, unit)
        for v, (unit, top) in zip(values, (("m", MAX_SIGMA_M), ("deg", MAX_SIGMA_DEG)),
                                  strict=False)
    ]
    sigma_deg = sigmas[1] if len(sigmas) == 2 else DEFAULT_SIGMA_DEG
    return FaultSpec(POSE_NOISE, 0.0, sigma_m=sigmas[0], sigma_deg=sigma_deg)


_LOCALIZATION_SHAPES: dict[str, tuple[str, tuple[tuple[str, float], ...]]] = {
    ODOM_NOISE: ("takes K and optionally K_ROT", (("K", 1.0), ("K_ROT", 1.0))),
    LIDAR_NOISE: ("takes a range sigma in metres", (("SIGMA", MAX_LIDAR_SIGMA),)),
    LIDAR_DROPOUT: ("takes a probability per beam", (("P", 1.0),)),
    KIDNAP: ("takes the sim time in seconds", (("T", MAX_KIDNAP_TIME),)),
}
"""Per localisation fault: what it takes, and each number's name and upper bound."""


def _parse_localization_fault(
    kind: str, values: list[str], bad: Callable[[str], InputError]
) -> FaultSpec:
    """The numbers of ``odom_noise``, ``lidar_noise``, ``lidar_dropout`` or ``kidnap``."""
    what, shape = _LOCALIZATION_SHAPES[kind]
    if not 1 <= len(values) <= len(shape):
        raise bad(f"{kind} {what}")
    out = [_bounded(v, name, top, bad) for v, (name, top) in zip(values, shape, strict=False)]
    if kind == ODOM_NOISE and len(out) == 1:
        out.append(out[0])
    return FaultSpec(kind, 0.0, values=tuple(out))


def localization_faults(specs: list[FaultSpec]) -> list[FaultSpec]:
    """The faults of ``specs`` that need localisation."""
    return [s for s in specs if s.kind in LOCALIZATION_FAULTS]


def _close(word: str, choices: list[str]) -> str:
    matches = difflib.get_close_matches(word, choices, n=3, cutoff=0.5)
    return " (did you mean " + ", ".join(f"'{m}'" for m in matches) + "?)" if matches else ""


def check_targets(specs: list[FaultSpec], names: set[str], ids: set[str]) -> None:
    """InputError for each node failure aimed at no node of the tree (by name or node ID)."""
    problems = []
    for spec in specs:
        if spec.kind != "failure" or spec.target in names or spec.target in ids:
            continue
        known = sorted(names | ids)
        hint = _close(spec.target, known)
        if not hint:
            shown = ", ".join(known[:12]) + (", ..." if len(known) > 12 else "")
            hint = f"; the tree's node names and IDs: {shown}"
        problems.append(Problem(
            "--inject", None,
            f"'{spec.text()}': no node of the tree is named '{spec.target}' or has that node "
            f"ID{hint}"))
    if problems:
        raise InputError(problems)


@dataclass
class FaultEvent:
    """One injected fault, for the report."""

    kind: str
    target: str
    sim_time: float
    note: str = ""
    """What became of the fault when it could not act as drawn (for instance no crate fell)."""


@dataclass(frozen=True)
class PoseOffset:
    """The error of the perceived pose of one object: a shift in the world's x and y (m) and a
    turn about the vertical through the object's centre (rad)."""

    dx: float
    dy: float
    dyaw: float

    def text(self) -> str:
        return (
            f"dx={self.dx * 1000:+.1f} mm, dy={self.dy * 1000:+.1f} mm, "
            f"dyaw={math.degrees(self.dyaw):+.2f} deg"
        )


@dataclass
class FaultInjector:
    """Draws the faults of one run from a generator seeded by the run's seed."""

    specs: list[FaultSpec]
    seed: int = 0
    clock: Clock | None = None
    events: list[FaultEvent] = field(default_factory=list)
    pending_blocks: dict[str, PendingBlock] = field(default_factory=dict)
    """Per robot, a drawn ``block`` whose crate has not fallen yet (see :meth:`defer_block`)."""

    def __post_init__(self) -> None:
        self._rng = np.random.default_rng([int(self.seed) & 0xFFFFFFFF, 0xFA17])
        self._offsets: dict[str, PoseOffset] = {}

    def _now(self) -> float:
        return float(self.clock.now()) if self.clock is not None else 0.0

    def _draw(self, p: float) -> bool:
        return bool(self._rng.random() < p)

    def targets(self) -> set[str]:
        return {s.target for s in self.specs if s.kind == "failure"}

    def node_fails(self, name: str, node_id: str) -> bool:
        """Called when a node starts; True when it must fail this time."""
        for spec in self.specs:
            if (
                spec.kind == "failure"
                and spec.target in (name, node_id)
                and self._draw(spec.probability)
            ):
                self.events.append(FaultEvent("failure", spec.target, self._now()))
                return True
        return False

    def _world_fault(self, kind: str, what: str) -> bool:
        for spec in self.specs:
            if spec.kind == kind and self._draw(spec.probability):
                self.events.append(FaultEvent(kind, what, self._now()))
                return True
        return False

    def slip(self, object_name: str) -> bool:
        """Called once per carry of ``object_name``; True when it must slip out."""
        return self._world_fault("slip", object_name)

    def block(self, route: str) -> bool:
        """Called once per navigation; True when an obstacle must fall on the route."""
        return self._world_fault("block", route)

    def pose_offset(self, object_name: str) -> PoseOffset | None:
        """The perception error of ``object_name`` for this episode (None without
        ``pose_noise``). Drawn the first time it is asked for, from a generator of its own
        seeded by the run's seed and the object's name (so the draw does not depend on what
        else was drawn before), and kept for the rest of the episode."""
        spec = next((s for s in self.specs if s.kind == POSE_NOISE), None)
        if spec is None:
            return None
        offset = self._offsets.get(object_name)
        if offset is None:
            rng = np.random.default_rng(
                [int(self.seed) & 0xFFFFFFFF, 0x9053, zlib.crc32(object_name.encode())]
            )
            dx, dy = rng.normal(0.0, spec.sigma_m, size=2) if spec.sigma_m > 0 else (0.0, 0.0)
            dyaw = rng.normal(0.0, math.radians(spec.sigma_deg)) if spec.sigma_deg > 0 else 0.0
            offset = PoseOffset(float(dx), float(dy), float(dyaw))
            self._offsets[object_name] = offset
            self.events.append(FaultEvent(POSE_NOISE, object_name, self._now(), offset.text()))
        return offset

    def defer_block(self, robot: str, block: PendingBlock) -> None:
        """Keep ``block`` until ``robot`` comes near its place (:meth:`due_block`); a robot has
        at most one pending crate (a later draw replaces an earlier one that never fell)."""
        self.pending_blocks[robot] = block

    def due_block(self, robot: str, x: float, y: float) -> PendingBlock | None:
        """The pending crate of ``robot`` when (``x``, ``y``) is within :data:`BLOCK_NEAR` of
        its place (it is then no longer pending), else None."""
        block = self.pending_blocks.get(robot)
        if block is None or np.hypot(block.x - x, block.y - y) > BLOCK_NEAR:
            return None
        del self.pending_blocks[robot]
        return block

    def report(self) -> list[dict[str, Any]]:
        out: list[dict[str, Any]] = []
        for e in self.events:
            row: dict[str, Any] = {"kind": e.kind, "target": e.target,
                                   "sim_time": round(e.sim_time, 3)}
            if e.note:
                row["note"] = e.note
            out.append(row)
        return out


# -- node failures ------------------------------------------------------------------------------


@dataclass
class FailingStart:
    """A node's own tick (``tick_node``) behind the draw of an injected failure.

    Each time the node starts (it is IDLE and its pre-conditions let it run), the injector draws
    for the node's name and ID; on a hit the node fails at once with :data:`INJECTED_REASON`,
    without running, and its post-condition scripts run as for any failure.
    """

    node: BtNode
    tick: Callable[[], NodeStatus]
    injector: FaultInjector

    def __call__(self) -> NodeStatus:
        node = self.node
        if node.bt_status is NodeStatus.IDLE and self.injector.node_fails(
            node.name, node.NODE_ID
        ):
            node.feedback_message = INJECTED_REASON
            return NodeStatus.FAILURE
        return self.tick()


def inject_node_failures(tree: Tree, injector: FaultInjector) -> int:
    """Wrap the own tick of every node of ``tree`` that a ``NAME:failure:P`` fault targets;
    returns how many were wrapped. The wrapping is on the node instance only: the tree keeps its
    nodes, order, names, IDs and XML.

    Raises InputError (see :func:`check_targets`) when a fault targets no node of the tree.
    """
    nodes = tree.nodes()
    check_targets(injector.specs, {n.name for n in nodes}, {n.NODE_ID for n in nodes})
    targets = injector.targets()
    wrapped = 0
    for node in nodes:
        if node.name in targets or node.NODE_ID in targets:
            node.tick_node = FailingStart(node, node.tick_node, injector)  # type: ignore[method-assign]
            wrapped += 1
    return wrapped


# -- world faults -------------------------------------------------------------------------------


@dataclass(frozen=True)
class PendingSlip:
    """An injected slip due at sim time ``at``: ``object_name`` will slip out of the grasp."""

    at: float
    object_name: str


def plan_slip(injector: FaultInjector, object_name: str, started_at: float) -> PendingSlip | None:
    """Draw the ``slip`` fault for a carry of ``object_name`` that started at ``started_at``."""
    if not injector.slip(object_name):
        return None
    return PendingSlip(started_at + SLIP_AFTER, object_name)


def slip_out(world: World, robot: Robot, slip: PendingSlip) -> None:
    """The injected slip: the attach joint goes and the fingers open."""
    if world.attachments.is_attached(slip.object_name):
        world.attachments.detach(slip.object_name)
    robot.set_gripper(robot.description.gripper.max_opening)


@dataclass(frozen=True)
class PendingBlock:
    """A ``block`` fault drawn for a route: a crate is due at (``x``, ``y``) on it."""

    x: float
    y: float
    route: str


def plan_block(injector: FaultInjector, polyline: Any, route: str) -> PendingBlock | None:
    """Draw the ``block`` fault for a navigation along ``polyline`` (rows x, y, ...) to
    ``route``; where the crate is due when it was drawn.

    The crate's place is the middle point of the route that is at least
    :data:`BLOCK_CLEARANCE` from both ends (a route with no such point gets none, and nothing is
    drawn): the fault tests going around an obstacle, not a goal made unreachable.
    """
    if not injector.specs or polyline is None or len(polyline) < 2:
        return None
    pts = np.asarray(polyline)[:, :2]
    far = (np.linalg.norm(pts - pts[0], axis=1) >= BLOCK_CLEARANCE) & (
        np.linalg.norm(pts - pts[-1], axis=1) >= BLOCK_CLEARANCE
    )
    if not far.any() or not injector.block(route):
        return None
    candidates = np.flatnonzero(far)
    x, y = pts[candidates[len(candidates) // 2]]
    return PendingBlock(float(x), float(y), route)


def drop_crate(world: World, injector: FaultInjector, block: PendingBlock) -> str | None:
    """Drop the crate of ``block``: it appears :data:`CRATE_DROP_HEIGHT` above the floor at its
    place and falls. Returns the crate's name, or None when it could not appear there (it would
    start inside a body; the fault's event says so)."""
    n = sum(1 for name in world.movable if name.startswith("dropped_crate"))
    spec = BodySpec(
        name=f"dropped_crate_{n}",
        movable=True,
        parts=[Part("box", (BLOCK_SIZE,) * 3, colour=COLOURS["brown"])],
        urdf=None,
        pose=Pose3D((block.x, block.y, BLOCK_SIZE / 2 + CRATE_DROP_HEIGHT)),
        planar=False,
        mass=CRATE_MASS,
        friction=CRATE_FRICTION,
        colour=COLOURS["brown"],
        randomize=Range2D(),
        line=0,
    )
    try:
        world.spawn(spec)
    except ValueError as exc:  # it would start inside a body, or the name is taken
        for event in reversed(injector.events):
            if event.kind == "block" and event.target == block.route:
                event.note = f"no crate fell: {exc}"
                break
        return None
    return spec.name


def block_route(world: World, injector: FaultInjector, polyline: Any, route: str) -> str | None:
    """The ``block`` fault for a navigation along ``polyline`` to ``route``, at once: drawn as
    :func:`plan_block` says, the crate falls now (:func:`drop_crate`). Returns the crate's name,
    or None when none fell."""
    block = plan_block(injector, polyline, route)
    return drop_crate(world, injector, block) if block is not None else None
