"""World files written for the sensing tests."""

from __future__ import annotations

from pathlib import Path

from bt_manip.sim.world import World
from bt_manip.sim.world_spec import BodySpec, Part, Pose3D, Range2D

ROOM = """\
name: laser_room
walls:
  - {name: south, from: [-3.05, -2.05], to: [3.05, -2.05], thickness: 0.1, height: 1.0}
  - {name: north, from: [-3.05, 2.05], to: [3.05, 2.05], thickness: 0.1, height: 1.0}
  - {name: west, from: [-3.05, -2.0], to: [-3.05, 2.0], thickness: 0.1, height: 1.0}
  - {name: east, from: [3.05, -2.0], to: [3.05, 2.0], thickness: 0.1, height: 1.0}
furniture:
  - {name: drum, shape: cylinder, radius: 0.3, height: 0.8, pose: [2.0, 1.0, 0.0]}
  - {name: chest, shape: box, size: [0.6, 0.4, 0.8], pose: [2.0, -1.0, 0.5235987755982988]}
  - name: shelf
    pose: {xyz: [1.2, 0.0, 0.0]}
    parts:
      - {shape: box, size: [0.4, 0.6, 0.1], xyz: [0.0, 0.0, 0.6]}
robots:
  - name: husky
    description: husky_ur3
    pose: [0.0, 0.0, 0.0]
    arm_state: tuck
"""
"""A 6 x 4 m room (inner faces x = +-3, y = +-2) with a drum (cylinder, centre (2, 1),
r 0.3), a chest (0.6 x 0.4 box at (2, -1) turned 30 deg) and a shelf whose board (z 0.55 to
0.65) floats above the Husky's scan plane at x = 1.2."""


def spawn_held(world: World, name: str, size: tuple[float, float, float],
               below: float = 0.3) -> None:
    """A box ``size`` spawned ``below`` m under the Husky's grasp frame and attached to it
    (held, as a grasp leaves it), then the world stepped so it settles in the hand."""
    robot = world.robots["husky"]
    grasp, _ = robot.link_pose(robot.description.grasp_frame)
    box = BodySpec(name=name, movable=True, parts=[Part("box", size)], urdf=None,
                   pose=Pose3D((grasp[0], grasp[1], grasp[2] - below)), planar=False,
                   mass=0.2, friction=0.8, colour=(1, 0, 0, 1), randomize=Range2D(), line=0)
    world.spawn(box)
    assert world.attachments.attach("husky", name, max_distance=0.5).ok
    world.step(24)


def write(tmp: Path, text: str, name: str = "world.yaml") -> Path:
    path = tmp / name
    path.write_text(text)
    return path
