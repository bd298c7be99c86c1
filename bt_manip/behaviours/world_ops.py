"""World operations for trees: add and remove models while the task runs."""

from __future__ import annotations

import math
from typing import ClassVar

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction
from bt_manip.bt import registry
from bt_manip.sim.world_spec import COLOURS, BodySpec, Part, Pose3D, Range2D


@registry.register
class SpawnModel(RobotAction):
    """Adds a model to the world: one declared in the world file's ``models`` (at its pose,
    moved by the seeded ``randomize`` offset), or else a primitive given by the ports.

    For a primitive, ``pose`` is ``x;y;z;yaw`` (z of the centre); ``size`` the box extents
    ``x;y;z``, or ``radius;height`` for a cylinder, ``radius`` for a sphere; ``mass`` 0 makes
    it static.

    - SUCCESS when the model is in the world;
    - FAILURE when the name is taken, the shape is unknown or incomplete, or it would start
      inside another body.
    """

    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        "model": PortInformation(str, True, "a model of the world file, or a new name"),
        "shape": PortInformation(str, False, "box, cylinder or sphere", "box"),
        "size": PortInformation(
            list[float], False, "box x;y;z, cylinder radius;height, sphere radius", []
        ),
        "pose": PortInformation(list[float], False, "x;y;z;yaw of its centre", []),
        "mass": PortInformation(float, False, "kg; 0 for a static model", 0.1),
        "colour": PortInformation(str, False, "colour name", "orange"),
        "friction": PortInformation(float, False, "lateral friction", 0.8),
    }

    def step(self) -> Status:
        name = self.get_input("model")
        if name in self.world.models:
            try:
                self.world.spawn_model(name)
            except ValueError as exc:
                raise ActionFailed(str(exc)) from None
            return Status.SUCCESS
        shape = self.get_input("shape")
        size = list(self.get_input("size"))
        need = {"box": 3, "cylinder": 2, "sphere": 1}
        if shape not in need:
            raise ActionFailed(f"shape must be box, cylinder or sphere, got '{shape}'")
        if len(size) != need[shape] or any(v <= 0 for v in size):
            raise ActionFailed(f"a {shape} needs {need[shape]} positive size values, got {size}")
        dims = {
            "box": tuple(size),
            "cylinder": (size[0], size[0], size[1]),
            "sphere": (size[0], size[0], 2 * size[0]),
        }[shape]
        pose = list(self.get_input("pose"))
        if len(pose) != 4:
            raise ActionFailed(f"pose takes x;y;z;yaw, got {pose}")
        colour = self.get_input("colour")
        if colour not in COLOURS:
            raise ActionFailed(f"unknown colour '{colour}'; known: {', '.join(sorted(COLOURS))}")
        mass = float(self.get_input("mass"))
        half = math.sin(pose[3] / 2), math.cos(pose[3] / 2)
        spec = BodySpec(
            name=self.get_input("model"),
            movable=mass > 0,
            parts=[Part(shape, dims, colour=COLOURS[colour])],
            urdf=None,
            pose=Pose3D((pose[0], pose[1], pose[2]), (0.0, 0.0, half[0], half[1])),
            planar=False,
            mass=mass,
            friction=float(self.get_input("friction")),
            colour=COLOURS[colour],
            randomize=Range2D(),
            line=self.xml_line or 0,
        )
        try:
            self.world.spawn(spec)
        except ValueError as exc:
            raise ActionFailed(str(exc)) from None
        return Status.SUCCESS


@registry.register
class DeleteModel(RobotAction):
    """Removes a model (movable object or furniture) from the world.

    - SUCCESS when it is gone (it is let go first if attached);
    - FAILURE when there is no such model.
    """

    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        "model": PortInformation(str, True, "name of the model to remove"),
    }

    def step(self) -> Status:
        try:
            self.world.remove(self.get_input("model"))
        except KeyError as exc:
            raise ActionFailed(str(exc.args[0])) from None
        return Status.SUCCESS
