"""RoboPlan's side of ``benchmarks/motion_planning.py``, run by the interpreter of the peers' venv
(RoboPlan pins ``pin < 4.2``, so it lives apart from bt-manip's environment). Standalone: numpy
and roboplan only, no bt_manip.

    python motion_planning_roboplan.py JOB.json RESULTS.json

JOB.json: ``urdf``, ``srdf``, ``group``, ``joints`` (the group's, in order), ``step``,
``time_limit_s``, ``seed``, ``problems`` (each ``id``, ``obstacles`` [``name``, ``shape`` box /
cylinder / sphere, ``size`` as bt-manip's Obstacle, ``pose`` 4x4], ``start``, ``goal``,
``locked`` {joint: value}). RESULTS.json: per problem ``id``, ``solved``, ``plan_ms`` (RRT-
Connect), ``shortcut_ms`` (RoboPlan's PathShortcutter at the same step), ``path`` (waypoints in
the order of ``joints``) or null, ``error``.
"""

from __future__ import annotations

import itertools
import json
import sys
import time
from pathlib import Path

import numpy as np
from roboplan.core import (
    Box,
    Cylinder,
    JointConfiguration,
    PathShortcutter,
    PathShortcuttingOptions,
    Scene,
    Sphere,
    loadUrdfSceneDescription,
)
from roboplan.rrt import RRT, RRTOptions

COLOUR = np.array([0.5, 0.5, 0.5, 1.0])


def scene_of(job: dict, problem: dict) -> Scene:
    urdf = Path(job["urdf"])
    scene = Scene("mbm", loadUrdfSceneDescription(str(urdf), [str(urdf.parent)]))
    if job.get("srdf"):
        scene.importSrdf(Path(job["srdf"]).read_text())
    for ob in problem["obstacles"]:
        pose = np.asfortranarray(np.asarray(ob["pose"], dtype=float))
        size = ob["size"]
        if ob["shape"] == "box":
            scene.addBoxGeometry(ob["name"], "universe", Box(*size), pose, COLOUR)
        elif ob["shape"] == "cylinder":
            scene.addCylinderGeometry(ob["name"], "universe", Cylinder(size[0], size[1]), pose,
                                      COLOUR)
        else:
            scene.addSphereGeometry(ob["name"], "universe", Sphere(size[0]), pose, COLOUR)
    names = [ob["name"] for ob in problem["obstacles"]]
    if len(names) > 1:  # the scene's objects may touch one another: only the robot matters
        scene.setCollisions(list(itertools.combinations(names, 2)), False)
    joints = scene.getJointNames()
    full = scene.getCurrentJointPositions()
    index = scene.getJointPositionIndices(joints)
    for name, k in zip(joints, index, strict=True):
        if name in problem["locked"]:
            full[k] = problem["locked"][name]
    scene.setJointPositions(full)
    return scene


def solve(job: dict, problem: dict) -> dict:
    scene = scene_of(job, problem)
    joints = job["joints"]
    options = RRTOptions(group_name=job["group"], max_nodes=1_000_000,
                         collision_check_step_size=job["step"],
                         max_planning_time=job["time_limit_s"], rrt_connect=True)
    rrt = RRT(scene, options)
    rrt.setRngSeed(job["seed"])
    start = JointConfiguration(joints, np.asarray(problem["start"], dtype=float))
    goal = JointConfiguration(joints, np.asarray(problem["goal"], dtype=float))
    began = time.perf_counter()
    try:
        path = rrt.plan(start, goal)
    except Exception as exc:  # RoboPlan reports failure as an exception
        return {"id": problem["id"], "solved": False, "plan_ms": None, "shortcut_ms": None,
                "path": None, "error": str(exc)[:300]}
    planned = time.perf_counter()
    if path is None or len(path.positions) == 0:
        return {"id": problem["id"], "solved": False, "plan_ms": None, "shortcut_ms": None,
                "path": None, "error": "no path"}
    shortcutter = PathShortcutter(scene, PathShortcuttingOptions(
        group_name=job["group"], max_step_size=job["step"], seed=job["seed"]))
    short = shortcutter.shortcut(path)
    done = time.perf_counter()
    order = [list(short.joint_names).index(j) for j in joints]
    waypoints = [[float(np.asarray(q)[k]) for k in order] for q in short.positions]
    return {"id": problem["id"], "solved": True, "plan_ms": (planned - began) * 1e3,
            "shortcut_ms": (done - planned) * 1e3, "path": waypoints, "error": ""}


def main() -> int:
    job = json.loads(Path(sys.argv[1]).read_text())
    results = [solve(job, problem) for problem in job["problems"]]
    Path(sys.argv[2]).write_text(json.dumps(results))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
