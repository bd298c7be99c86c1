"""A tiny MotionBenchMaker family for the tests: a Panda (example-robot-data) left of a wall,
its goal right of it."""

from __future__ import annotations

from pathlib import Path

from bt_manip.sim.assets import example_robot_data_share

PANDA = example_robot_data_share() / "example-robot-data/robots/panda_description"
URDF = PANDA / "urdf" / "panda.urdf"
SRDF = PANDA / "srdf" / "panda.srdf"
ARM = [f"panda_joint{i}" for i in range(1, 8)]
LEFT = [1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.785]
RIGHT = [-1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.785]

SCENE = """\
name: ""
robot_model_name: panda
world:
  collision_objects:
    - id: wall
      primitives:
        - type: box
          dimensions: [0.3, 0.05, 0.9]
      primitive_poses:
        - position: [0.5, 0.0, 0.45]
          orientation: [0, 0, 0, 1]
"""


def request_text(start: list[float], goal: list[float], group: str = "arm") -> str:
    names = [*ARM, "panda_finger_joint1", "panda_finger_joint2"]
    constraints = "\n".join(f"      - joint_name: {n}\n        position: {v}"
                            for n, v in zip(ARM, goal, strict=True))
    return (f"group_name: {group}\nstart_state:\n  joint_state:\n"
            f"    name: [{', '.join(names)}]\n"
            f"    position: [{', '.join(map(str, [*start, 0.065, 0.065]))}]\n"
            f"goal_constraints:\n  - joint_constraints:\n{constraints}\n")


def write_family(folder: Path, n: int = 1) -> Path:
    """``folder`` with ``n`` problems: left of the wall to right of it."""
    folder.mkdir(parents=True)
    for k in range(1, n + 1):
        (folder / f"scene{k:04d}.yaml").write_text(SCENE)
        (folder / f"request{k:04d}.yaml").write_text(request_text(LEFT, RIGHT))
    return folder
