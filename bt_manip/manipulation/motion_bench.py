"""Arm motion planning on MotionBenchMaker problems: plan each one, check the path again on the
exact meshes, and sum the outcomes up per scene family.

For each problem (a ``sceneNNNN.yaml`` and its ``requestNNNN.yaml``, :mod:`.mbm`):

- the planned joints are the SRDF group's (a ``chain`` from its base link to its tip link, or
  ``joint`` elements; default group: the request's ``group_name``), or without an SRDF the
  joints the request's goal constrains; every other joint is locked at its start value,
  clipped into its limits;
- a :class:`~.collision_scene.CollisionScene` holds the robot (self-collision pairs the SRDF
  disables left out) and the scene's primitives, and :func:`~.rrt_connect.plan` (RRT-Connect,
  shortcutting, a re-check at ``validate_step``) looks for a path with a budget of collision
  checks; a wall-clock limit per problem can stop it too, for benchmarking only;
- the path is then checked by :func:`validate_path` on a scene of the exact meshes
  (``exact=True``) at :data:`VALIDATE_STEP` rad per joint along every segment: the same
  validator a benchmark applies to other planners' paths.

:func:`results_document` is the ``--out`` file of ``bt-manip motion-bench`` (schema
``motion-bench``); :func:`family_summary` the figures it prints.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import defusedxml.ElementTree as SafeET
import numpy as np
import pinocchio as pin

from bt_manip.errors import InputError
from bt_manip.manipulation.collision_scene import CollisionScene, SceneError, srdf_pairs
from bt_manip.manipulation.mbm import Problem, family_problems, read_problem
from bt_manip.manipulation.rrt_connect import PlanError, PlanOptions, path_length, plan
from bt_manip.sim.compose import composed_urdf

__all__ = [
    "PLANNERS", "SCHEMA_VERSION", "VALIDATE_STEP", "BenchOptions", "Outcome", "Robot",
    "Setup", "family_folders", "family_summary", "load_robot", "results_document",
    "run_bench", "run_problem", "scene_for", "setup_problem", "validate_path",
]

SCHEMA_VERSION = 1
VALIDATE_STEP = 0.01
"""Largest joint move (rad) between two configurations the validator checks."""
PLANNERS = ("rrtconnect",)


@dataclass(frozen=True)
class BenchOptions:
    """How each problem is planned. ``time_limit_s`` stops a problem by wall clock (None: the
    count budget ``max_checks`` alone)."""

    planner: str = "rrtconnect"
    time_limit_s: float | None = 1.0
    seed: int = 0
    step: float = 0.05
    max_checks: int = 200_000
    shortcut_rounds: int = 20


@dataclass(frozen=True)
class Robot:
    """A robot to plan for: its URDF, the SRDF's disabled pairs and groups, the URDF's joints
    (in model order) with their limits, and the group to plan (None: each request's)."""

    name: str
    urdf: Path
    srdf: Path | None
    group: str | None
    allowed: frozenset[frozenset[str]]
    joint_order: tuple[str, ...]
    limits: dict[str, tuple[float, float]]
    groups: dict[str, tuple[str, ...]] = field(default_factory=dict)


@dataclass(frozen=True)
class Setup:
    """One problem made ready to plan: the joints, the locked ones and both ends."""

    joints: tuple[str, ...]
    locked: dict[str, float]
    start: np.ndarray
    goal: np.ndarray


@dataclass(frozen=True)
class Outcome:
    """What planning one problem gave; ``path`` in the order of ``joint_names`` (None when
    unsolved), ``reason`` why it is unsolved."""

    family: str
    scene: str
    request: str
    solved: bool
    valid: bool
    planning_ms: float | None
    path_length_rad: float | None
    joint_names: tuple[str, ...]
    path: list[list[float]] | None
    reason: str = ""


# -- the robot and its groups --------------------------------------------------------------------
def _urdf_joints(urdf: Path) -> tuple[str, dict[str, tuple[str, str, str]]]:
    """The robot's name and its joints by child link: (joint, parent link, type)."""
    try:
        root = SafeET.parse(str(urdf)).getroot()
    except Exception as exc:  # defusedxml and expat raise several unrelated types
        raise InputError.single(str(urdf), None, f"the URDF does not parse: {exc}") from None
    by_child = {}
    for joint in root.iter("joint"):
        parent, child = joint.find("parent"), joint.find("child")
        if parent is not None and child is not None:
            by_child[child.get("link", "")] = (joint.get("name", ""), parent.get("link", ""),
                                               joint.get("type", ""))
    return root.get("name", urdf.stem), by_child


def _srdf_groups(
    srdf: Path, by_child: dict[str, tuple[str, str, str]]
) -> dict[str, tuple[str, ...]]:
    """Each SRDF group's movable joints: its chains (base link to tip link), joints and
    subgroups, in the order they are listed."""
    try:
        root = SafeET.parse(str(srdf)).getroot()
    except Exception as exc:
        raise InputError.single(str(srdf), None, f"the SRDF does not parse: {exc}") from None
    elements = {g.get("name", ""): g for g in root.findall("group")}
    out: dict[str, tuple[str, ...]] = {}

    def joints_of(name: str, seen: tuple[str, ...]) -> tuple[str, ...]:
        if name in out:
            return out[name]
        if name in seen or name not in elements:
            raise InputError.single(str(srdf), None, f"group '{name}' is not defined (or is "
                                    "its own subgroup)")
        found: list[str] = []
        for el in elements[name]:
            if el.tag == "chain":
                base, link, chain = el.get("base_link", ""), el.get("tip_link", ""), []
                while link != base:
                    if link not in by_child:
                        raise InputError.single(str(srdf), None, f"group '{name}': no chain "
                                                f"from {el.get('base_link')} to "
                                                f"{el.get('tip_link')} in the URDF")
                    joint, link, kind = by_child[link]
                    if kind not in ("fixed", "floating", "planar"):
                        chain.append(joint)
                found += chain[::-1]
            elif el.tag == "joint":
                found.append(el.get("name", ""))
            elif el.tag == "group":
                found += joints_of(el.get("name", ""), (*seen, name))
        out[name] = tuple(dict.fromkeys(found))
        return out[name]

    for name in elements:
        joints_of(name, ())
    return out


def load_robot(urdf: Path, srdf: Path | None = None, group: str | None = None) -> Robot:
    """The robot of ``urdf`` (and ``srdf``); InputError on a file that cannot be read."""
    for path in (urdf, srdf):
        if path is not None and not path.is_file():
            raise InputError.single(str(path), None, "no such file")
    name, by_child = _urdf_joints(urdf)
    try:
        model = pin.buildModelFromUrdf(str(composed_urdf(urdf)))
    except (ValueError, RuntimeError) as exc:
        raise InputError.single(str(urdf), None, f"the URDF does not load: {exc}") from None
    order, limits = [], {}
    for jid in range(1, model.njoints):
        joint = model.joints[jid]
        if joint.nq == 1:
            jname = model.names[jid]
            order.append(jname)
            limits[jname] = (float(model.lowerPositionLimit[joint.idx_q]),
                             float(model.upperPositionLimit[joint.idx_q]))
    groups = _srdf_groups(srdf, by_child) if srdf is not None else {}
    if group is not None and srdf is not None and group not in groups:
        raise InputError.single(str(srdf), None, f"no group '{group}' (groups: "
                                f"{', '.join(groups) or 'none'})")
    allowed = frozenset(srdf_pairs(srdf)) if srdf is not None else frozenset()
    return Robot(name, urdf, srdf, group, allowed, tuple(order), limits, groups)


def setup_problem(robot: Robot, problem: Problem) -> Setup:
    """The joints to plan, the locked values and both ends of ``problem``."""
    request = f"{problem.family}/{problem.request}"
    if robot.srdf is not None:
        group = robot.group or problem.group
        if group not in robot.groups:
            raise InputError.single(request, None, f"group '{group}' is not in {robot.srdf.name}"
                                    f" (groups: {', '.join(robot.groups) or 'none'})")
        wanted = set(robot.groups[group])
    else:
        wanted = set(problem.goal)
    unknown = sorted(wanted - set(robot.joint_order))
    if unknown:
        raise InputError.single(request, None, f"joint(s) {', '.join(unknown)} not in "
                                f"{robot.urdf.name}")
    joints = tuple(j for j in robot.joint_order if j in wanted)
    for end, values in (("start", problem.start), ("goal", problem.goal)):
        missing = [j for j in joints if j not in values]
        if missing:
            raise InputError.single(request, None, f"the {end} gives no position for "
                                    f"{', '.join(missing)}")
    locked = {}
    for name, value in problem.start.items():
        if name in robot.limits and name not in wanted:
            lo, hi = robot.limits[name]
            locked[name] = float(np.clip(value, lo, hi)) if lo <= hi else value
    start = np.array([problem.start[j] for j in joints], dtype=float)
    goal = np.array([problem.goal[j] for j in joints], dtype=float)
    return Setup(joints, locked, start, goal)


def scene_for(robot: Robot, setup: Setup, problem: Problem, exact: bool = False) -> CollisionScene:
    """The planning scene of ``problem`` (``exact``: meshes only, as the validator checks)."""
    try:
        scene = CollisionScene(robot.urdf, setup.joints, locked=setup.locked,
                               allowed=robot.allowed, exact=exact)
        for obstacle in problem.obstacles:
            scene.add_obstacle(obstacle)
    except SceneError as exc:
        raise InputError.single(f"{problem.family}/{problem.scene}", None, str(exc)) from None
    return scene


# -- planning and validating ---------------------------------------------------------------------
def validate_path(scene: CollisionScene, path: Sequence[np.ndarray], start: np.ndarray,
                  goal: np.ndarray, step: float = VALIDATE_STEP) -> bool:
    """True when ``path`` runs from ``start`` to ``goal`` within the joint limits and every
    segment is free at ``step`` rad per joint (the first configuration checked too)."""
    if len(path) < 1:
        return False
    q = [np.asarray(p, dtype=float) for p in path]
    if not (np.allclose(q[0], start, atol=1e-6) and np.allclose(q[-1], goal, atol=1e-6)):
        return False
    if not all(scene.within_limits(p) for p in q):
        return False
    return scene.first_blocked(q, step) is None


def _deadline(limit_s: float | None, every: int = 8) -> Callable[[], bool] | None:
    """A stop callback true once ``limit_s`` seconds have passed (the clock read every
    ``every`` calls)."""
    if limit_s is None:
        return None
    end = time.perf_counter() + limit_s
    calls = itertools.count()

    def stop() -> bool:
        return next(calls) % every == 0 and time.perf_counter() > end

    return stop


def run_problem(robot: Robot, scene_file: Path, request_file: Path,
                options: BenchOptions = BenchOptions()) -> Outcome:
    """Plan one problem and validate the path. InputError on a file that cannot be read."""
    problem = read_problem(scene_file, request_file)
    setup = setup_problem(robot, problem)
    scene = scene_for(robot, setup, problem)
    plan_options = PlanOptions(step=options.step, max_checks=options.max_checks,
                               shortcut_rounds=options.shortcut_rounds)
    rng = np.random.default_rng([options.seed, _number(scene_file.name)])
    began = time.perf_counter()
    try:
        result = plan(scene, setup.start, setup.goal, rng, plan_options,
                      _deadline(options.time_limit_s))
    except PlanError as exc:
        return Outcome(problem.family, problem.scene, problem.request, False, False, None, None,
                       setup.joints, None, str(exc))
    elapsed_ms = (time.perf_counter() - began) * 1e3
    exact = scene_for(robot, setup, problem, exact=True)
    valid = validate_path(exact, result.path, setup.start, setup.goal)
    return Outcome(problem.family, problem.scene, problem.request, True, valid, elapsed_ms,
                   path_length(result.path), setup.joints,
                   [[float(v) for v in q] for q in result.path],
                   "" if valid else "the path touches at the validation step")


def _number(name: str) -> int:
    digits = "".join(c for c in name if c.isdigit())
    return int(digits) if digits else 0


def family_folders(root: Path) -> list[Path]:
    """``root`` when it holds problems, else its subfolders that do (sorted)."""
    if not root.is_dir():
        raise InputError.single(str(root), None, "no such folder")
    if any(root.glob("scene*.yaml")):
        return [root]
    folders = sorted(p for p in root.iterdir() if p.is_dir() and any(p.glob("scene*.yaml")))
    if not folders:
        raise InputError.single(str(root), None, "no sceneNNNN.yaml here nor in a subfolder")
    return folders


def run_bench(robot: Robot, folders: Iterable[Path], options: BenchOptions = BenchOptions(),
              limit: int | None = None,
              progress: Callable[[Outcome], None] | None = None) -> list[Outcome]:
    """Every problem of ``folders`` (the first ``limit`` of each when given), in order."""
    if options.planner not in PLANNERS:
        raise InputError.single("--planner", None, f"unknown planner '{options.planner}' "
                                f"(known: {', '.join(PLANNERS)})")
    out = []
    for folder in folders:
        for scene_file, request_file in family_problems(folder)[:limit]:
            outcome = run_problem(robot, scene_file, request_file, options)
            out.append(outcome)
            if progress is not None:
                progress(outcome)
    return out


# -- figures -------------------------------------------------------------------------------------
def _stats(values: Sequence[float]) -> dict[str, float | None]:
    if not values:
        return {"median": None, "mean": None, "p95": None}
    a = np.asarray(values, dtype=float)
    return {"median": float(np.median(a)), "mean": float(a.mean()),
            "p95": float(np.percentile(a, 95))}


def family_summary(outcomes: Sequence[Outcome]) -> dict[str, dict[str, object]]:
    """Per family and ``overall``: problems, solved, valid, and median / mean / p95 of the
    planning time (ms) and path length (rad) over the solved ones."""
    groups: dict[str, list[Outcome]] = {}
    for o in outcomes:
        groups.setdefault(o.family, []).append(o)
    groups["overall"] = list(outcomes)
    out: dict[str, dict[str, object]] = {}
    for name, items in groups.items():
        solved = [o for o in items if o.solved]
        out[name] = {
            "problems": len(items), "solved": len(solved),
            "valid": sum(o.valid for o in items),
            "planning_ms": _stats([o.planning_ms for o in solved if o.planning_ms is not None]),
            "path_length_rad": _stats([o.path_length_rad for o in solved
                                       if o.path_length_rad is not None]),
        }
    return out


def _fmt(value: object, digits: int) -> str:
    return "-" if not isinstance(value, float) or math.isnan(value) else f"{value:.{digits}f}"


def summary_lines(outcomes: Sequence[Outcome]) -> list[str]:
    """The table ``bt-manip motion-bench`` prints: one line per family and one overall."""
    rows = [f"{'family':<24} {'solved':>9} {'valid':>6} {'median ms':>10} {'mean ms':>9} "
            f"{'p95 ms':>9} {'median rad':>10} {'mean rad':>9} {'p95 rad':>8}"]
    for name, s in family_summary(outcomes).items():
        t, length = s["planning_ms"], s["path_length_rad"]
        assert isinstance(t, dict) and isinstance(length, dict)
        rows.append(
            f"{name:<24} {s['solved']:>4}/{s['problems']:<4} {s['valid']:>6} "
            f"{_fmt(t['median'], 1):>10} {_fmt(t['mean'], 1):>9} {_fmt(t['p95'], 1):>9} "
            f"{_fmt(length['median'], 2):>10} {_fmt(length['mean'], 2):>9} "
            f"{_fmt(length['p95'], 2):>8}")
    return rows


def results_document(robot: Robot, options: BenchOptions,
                     outcomes: Sequence[Outcome]) -> dict[str, object]:
    """The ``--out`` file (schema ``motion-bench``, version 1)."""
    return {
        "schema_version": SCHEMA_VERSION,
        "robot": robot.name,
        "planner": options.planner,
        "time_limit_s": options.time_limit_s,
        "seed": options.seed,
        "collision_step_rad": options.step,
        "validation_step_rad": VALIDATE_STEP,
        "problems": [
            {
                "family": o.family, "scene": o.scene, "request": o.request,
                "solved": o.solved, "valid": o.valid, "planning_ms": o.planning_ms,
                "path_length_rad": o.path_length_rad, "joint_names": list(o.joint_names),
                "path": o.path, "reason": o.reason,
            }
            for o in outcomes
        ],
    }
