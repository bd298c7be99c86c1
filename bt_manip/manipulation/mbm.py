"""MotionBenchMaker problems: a MoveIt planning scene and a motion plan request per problem.

A family folder (``problems/box_panda/``) holds ``sceneNNNN.yaml`` (a MoveIt ``PlanningScene``:
``world.collision_objects[]`` with ``primitives`` box [x, y, z] / cylinder [height, radius] /
sphere [radius] and ``primitive_poses`` position + quaternion x, y, z, w) and
``requestNNNN.yaml`` (a ``MotionPlanRequest``: ``start_state.joint_state`` names and positions,
``goal_constraints[0].joint_constraints[]``, ``group_name``). :func:`read_problem` reads one
pair into a :class:`Problem`; a file that does not hold what is needed raises
:class:`~bt_manip.errors.InputError` naming its line.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bt_manip.errors import InputError
from bt_manip.geometry import rotation_matrix
from bt_manip.manipulation.collision_scene import Obstacle
from bt_manip.sim.yaml_lines import LineDict, LineList, load_yaml

__all__ = ["Problem", "family_problems", "read_problem"]

MAX_OBJECTS = 10_000


@dataclass(frozen=True)
class Problem:
    """One planning problem: obstacles, start and goal (by joint name), the group planned."""

    family: str
    scene: str
    request: str
    group: str
    obstacles: tuple[Obstacle, ...]
    start: dict[str, float]
    goal: dict[str, float]


def _fail(path: Path, node: object, message: str) -> InputError:
    line = getattr(node, "line", None)
    return InputError.single(str(path), line or None, message)


def _mapping(path: Path, node: object, key: str) -> LineDict:
    value = node.get(key) if isinstance(node, dict) else None
    if not isinstance(value, LineDict):
        raise _fail(path, node, f"expected a mapping '{key}'")
    return value


def _numbers(path: Path, node: object, key: str, n: int | None = None) -> list[float]:
    value = node.get(key) if isinstance(node, dict) else None
    ok = isinstance(value, list) and all(
        isinstance(v, int | float) and not isinstance(v, bool) for v in value
    )
    if not ok or (n is not None and len(value) != n):  # type: ignore[arg-type]
        where = node.line_of(key) if isinstance(node, LineDict) else None
        count = f"{n} numbers" if n is not None else "a list of numbers"
        raise InputError.single(str(path), where, f"'{key}' must be {count}, got {value!r}")
    return [float(v) for v in value]  # type: ignore[union-attr]


def _obstacles(path: Path) -> tuple[Obstacle, ...]:
    data = load_yaml(path)
    world = _mapping(path, data, "world")
    objects = world.get("collision_objects") or []
    if not isinstance(objects, LineList) or len(objects) > MAX_OBJECTS:
        raise _fail(path, world, f"world.collision_objects must be a list (at most "
                    f"{MAX_OBJECTS})")
    out: list[Obstacle] = []
    for obj in objects:
        if not isinstance(obj, LineDict):
            raise _fail(path, objects, "each collision object must be a mapping")
        name = str(obj.get("id", f"object_{len(out)}"))
        prims = obj.get("primitives") or []
        poses = obj.get("primitive_poses") or []
        if not isinstance(prims, list) or not isinstance(poses, list) or len(prims) != len(poses):
            raise _fail(path, obj, f"'{name}': primitives and primitive_poses must be lists of "
                        "the same length")
        for k, (prim, pose) in enumerate(zip(prims, poses, strict=True)):
            kind = prim.get("type") if isinstance(prim, dict) else None
            dims = _numbers(path, prim, "dimensions")
            position = _numbers(path, pose, "position", 3)
            x, y, z, w = _numbers(path, pose, "orientation", 4)
            m = np.eye(4)
            m[:3, :3] = rotation_matrix((x, y, z, w))
            m[:3, 3] = position
            if kind == "box" and len(dims) == 3:
                size: tuple[float, ...] = tuple(dims)
            elif kind == "cylinder" and len(dims) == 2:
                size = (dims[1], dims[0])  # MoveIt: height, radius
            elif kind == "sphere" and len(dims) == 1:
                size = (dims[0],)
            else:
                raise _fail(path, prim, f"'{name}': primitive type {kind!r} with {len(dims)} "
                            "dimensions (box 3, cylinder 2, sphere 1)")
            label = name if len(prims) == 1 else f"{name}/{k}"
            out.append(Obstacle(label, str(kind), size, tuple(map(tuple, m))))
    return tuple(out)


def _joint_state(path: Path, node: object) -> dict[str, float]:
    names = node.get("name") if isinstance(node, dict) else None
    positions = _numbers(path, node, "position")
    if not isinstance(names, list) or len(names) != len(positions):
        raise _fail(path, node, "joint_state: name and position must be lists of one length")
    return {str(n): p for n, p in zip(names, positions, strict=True)}


def read_problem(scene: Path, request: Path) -> Problem:
    """The problem of one scene file and its request file."""
    obstacles = _obstacles(scene)
    data = load_yaml(request)
    start_state = _mapping(request, data, "start_state")
    start = _joint_state(request, _mapping(request, start_state, "joint_state"))
    goals = data.get("goal_constraints") if isinstance(data, dict) else None
    if not isinstance(goals, list) or not goals or not isinstance(goals[0], dict):
        raise _fail(request, data, "goal_constraints must hold one joint-space goal")
    constraints = goals[0].get("joint_constraints")
    if not isinstance(constraints, list) or not constraints:
        raise _fail(request, goals[0], "goal_constraints[0].joint_constraints is missing")
    goal: dict[str, float] = {}
    for c in constraints:
        name = c.get("joint_name") if isinstance(c, dict) else None
        value = c.get("position") if isinstance(c, dict) else None
        if not isinstance(name, str) or not isinstance(value, int | float):
            raise _fail(request, c, "a joint constraint needs joint_name and position")
        goal[name] = float(value)
    group = str(data.get("group_name", ""))
    return Problem(scene.parent.name, scene.name, request.name, group, obstacles, start, goal)


def family_problems(folder: Path) -> list[tuple[Path, Path]]:
    """(scene, request) file pairs of a family folder, in number order."""
    pairs = []
    for scene in sorted(folder.glob("scene*.yaml")):
        request = folder / scene.name.replace("scene", "request", 1)
        if not request.is_file():
            raise InputError.single(str(scene), None, f"no {request.name} beside it")
        pairs.append((scene, request))
    return pairs
