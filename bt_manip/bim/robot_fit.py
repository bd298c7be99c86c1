"""What a robot can install: its arm's reach map for top-down grasps, its gripper, its height.

An element to install is grasped from above by its top edge (see
:mod:`bt_manip.manipulation.grasps`), once from its stand at the stock and once more where it
is placed. :func:`robot_fit` measures, for the robot's arm, the reach map: at horizontal
distances just ahead of the front of the robot's footprint (where an element stands when the
robot faces it), the heights of the grasp frame, pointing straight down, that inverse
kinematics reaches together with the pre-grasp point :data:`APPROACH` above it (the way
PlanBaseForGrasp and PlanBaseForPlace come down). A top edge is within reach when the grasp
frame :data:`~bt_manip.manipulation.grasps.GRASP_DEPTH` below it is one of those heights. The
same survey reads the top of the robot with its arm tucked (the height it drives with).

The survey costs a few seconds (the IK solver is built, about 1500 solves); its result is kept
in the shared cache, keyed by the robot's composed URDF and descriptor, and reused.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from bt_manip.kinematics.arm_model import ArmModel
from bt_manip.kinematics.compiled import cache_dir
from bt_manip.kinematics.ik import IKOptions, IKSolver
from bt_manip.manipulation.grasps import GRASP_DEPTH, OPENING_MARGIN
from bt_manip.sim.compose import write_atomic_bytes
from bt_manip.sim.robot_description import RobotDescription

APPROACH = 0.12
"""The pre-grasp point's height (m) above the grasp: the base searches' default approach."""
HEIGHT_STEP = 0.02
"""Heights (m) of the reach map, from 0 to :data:`MAX_HEIGHT`."""
MAX_HEIGHT = 2.0
DISTANCES = tuple(round(0.02 + 0.05 * i, 3) for i in range(9))
"""Horizontal distances (m) of the grasp ahead of the front of the footprint."""
SURVEY_VERSION = 1
"""Part of the cache key: change it when the survey changes."""


@dataclass(frozen=True)
class RobotFit:
    """The robot's figures an element is checked against."""

    robot: str
    tucked_top: float
    """Top (m above the floor) of the robot with its arm in its ``tuck`` state (``home``
    without one)."""
    grasp_heights: tuple[tuple[float, float], ...]
    """Intervals (m) of grasp-frame heights reached pointing down, with the pre-grasp above."""
    max_opening: float
    """The gripper's widest opening (m)."""

    def top_edge_reached(self, top: float, height: float) -> bool:
        """Whether a top edge ``top`` m above the floor, of an element ``height`` m high, can
        be grasped from above."""
        grasp = top - min(GRASP_DEPTH, height / 2)
        return any(lo - 1e-9 <= grasp <= hi + 1e-9 for lo, hi in self.grasp_heights)

    def reach_text(self) -> str:
        """The reachable top edges, as text (``0.03-0.88 m``)."""
        if not self.grasp_heights:
            return "none"
        return ", ".join(f"{lo + GRASP_DEPTH:.2f}-{hi + GRASP_DEPTH:.2f} m"
                         for lo, hi in self.grasp_heights)

    def grips(self, thickness: float) -> bool:
        """Whether the fingers open wide enough round ``thickness`` m."""
        return thickness + OPENING_MARGIN <= self.max_opening + 1e-9


_MEMO: dict[str, RobotFit] = {}


def robot_fit(robot: RobotDescription) -> RobotFit:
    """The robot's :class:`RobotFit`: from memory, from the shared cache, or surveyed."""
    key = _key(robot)
    if key in _MEMO:
        return _MEMO[key]
    path = cache_dir() / "bim-fit" / f"{key}.json"
    fit: RobotFit | None = None
    try:
        data = json.loads(path.read_text())
        fit = RobotFit(
            str(data["robot"]), float(data["tucked_top"]),
            tuple((float(a), float(b)) for a, b in data["grasp_heights"]),
            float(data["max_opening"]),
        )
    except (OSError, ValueError, KeyError, TypeError):
        fit = None
    if fit is None:
        fit = _survey(robot)
        _store(path, fit)
    _MEMO[key] = fit
    return fit


def _key(robot: RobotDescription) -> str:
    digest = hashlib.sha256(f"bim-fit-{SURVEY_VERSION}:".encode())
    digest.update(robot.urdf_path.read_bytes())
    digest.update(robot.path.read_bytes())
    return digest.hexdigest()[:32]


def _store(path: Any, fit: RobotFit) -> None:
    """Write the survey atomically; a cache that cannot be written is skipped."""
    with contextlib.suppress(OSError):
        write_atomic_bytes(path, json.dumps(asdict(fit)).encode())


def _survey(robot: RobotDescription) -> RobotFit:
    return RobotFit(robot.name, _tucked_top(robot), _grasp_heights(robot),
                    robot.gripper.max_opening)


def _grasp_heights(robot: RobotDescription) -> tuple[tuple[float, float], ...]:
    """Heights reached (see the module docstring), as merged intervals."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(robot.urdf_path))
    root = next(f.name for f in model.frames if f.type == pin.FrameType.BODY)
    arm = ArmModel.from_model(model, root, robot.grasp_frame)
    ik = IKSolver(arm, IKOptions(free_axis="z", time_budget=None, max_restarts=30,
                                 diagnose=False))
    fp = robot.footprint
    front = fp.radius if fp.is_circle else fp.x_offset + fp.length / 2
    down = np.diag([1.0, -1.0, -1.0])
    heights = np.arange(0.0, MAX_HEIGHT + 1e-9, HEIGHT_STEP)
    reached = np.zeros(len(heights), dtype=bool)

    def solves(x: float, z: float) -> bool:
        target = np.eye(4)
        target[:3, :3] = down
        target[:3, 3] = [x, 0.0, z]
        return bool(ik.solve(target).success)

    for d in DISTANCES:
        x = front + d
        for i, z in enumerate(heights):
            if not reached[i] and solves(x, float(z)) and solves(x, float(z) + APPROACH):
                reached[i] = True
    out: list[tuple[float, float]] = []
    for index in np.flatnonzero(reached):
        z = round(float(heights[index]), 3)
        if out and math.isclose(out[-1][1] + HEIGHT_STEP, z, abs_tol=1e-6):
            out[-1] = (out[-1][0], z)
        else:
            out.append((z, z))
    return tuple(out)


def _tucked_top(robot: RobotDescription) -> float:
    """Top of the robot's bounding boxes with the arm tucked, standing on the floor."""
    import pybullet as p

    client = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(str(robot.urdf_path), [0.0, 0.0, robot.spawn_height],
                          physicsClientId=client)
        joints = {
            p.getJointInfo(body, j, physicsClientId=client)[1].decode(): j
            for j in range(p.getNumJoints(body, physicsClientId=client))
        }
        state = "tuck" if "tuck" in robot.states else "home"
        if state in robot.states:
            for name, value in zip(robot.arm.joints, robot.state(state), strict=True):
                if name in joints:
                    p.resetJointState(body, joints[name], value, physicsClientId=client)
        links = range(-1, p.getNumJoints(body, physicsClientId=client))
        top = max(float(p.getAABB(body, link, physicsClientId=client)[1][2]) for link in links)
        return round(top, 3)
    finally:
        p.disconnect(client)
