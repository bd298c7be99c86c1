"""World operations for trees: add and remove models while the task runs."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction
from bt_manip.bt import registry
from bt_manip.bt.node import AttributeCheck, closest
from bt_manip.bt.ports import NON_NEGATIVE, POSITIVE, Accepts, Literal, Port, count_of
from bt_manip.sim.world_spec import COLOURS, BodySpec, Part, Pose3D, Range2D

SHAPE_SIZES = {"box": 3, "cylinder": 2, "sphere": 1}
"""How many ``size`` values each primitive takes."""
_SIZE_MEANING = {"box": "x;y;z extents", "cylinder": "radius;height", "sphere": "radius"}


def size_count_problem(shape: str, size: list[float]) -> str | None:
    """What is wrong with the number of ``size`` values for ``shape`` (None if nothing)."""
    need = SHAPE_SIZES.get(shape)
    if need is None or not size or len(size) == need:
        return None
    return (f"a {shape} takes {need} size value{'s' if need > 1 else ''} "
            f"({_SIZE_MEANING[shape]}), got {len(size)}: {size}")


@registry.register
class SpawnModel(RobotAction):
    """Adds a model to the world: one declared in the world file's ``models`` (at its pose,
    moved by the seeded ``randomize`` offset), or else a primitive given by the ports.

    For a primitive, ``pose`` is ``x;y;z;yaw`` (z of the centre); ``size`` the box extents
    ``x;y;z``, or ``radius;height`` for a cylinder, ``radius`` for a sphere; ``mass`` 0 makes
    it static. A literal value a port cannot take (``mass="-1"``, ``shape="cone"``, three size
    values for a sphere...) is an error of the tree file, reported when it loads.

    - SUCCESS when the model is in the world;
    - FAILURE when the name is taken, the name is not a model of the world and no primitive
      is given, a value read from the blackboard is out of range, or the model would start
      inside another body.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "model": PortInformation(str, True, "a model of the world file, or a new name"),
        "shape": Port(str, False, "box, cylinder or sphere", "box",
                      Accepts(choices=tuple(SHAPE_SIZES))),
        "size": Port(list[float], False, "box x;y;z, cylinder radius;height, sphere radius (m)", [],
                     POSITIVE),
        "pose": Port(list[float], False, "x;y;z;yaw of its centre (m, rad; world)", [],
                     count_of(0, 4)),
        "mass": Port(float, False, "kg; 0 for a static model", 0.1, NON_NEGATIVE),
        "colour": Port(
            str, False, "colour name", "orange", Accepts(choices=tuple(sorted(COLOURS)))
        ),
        "friction": Port(float, False, "lateral friction coefficient", 0.8, NON_NEGATIVE),
    }

    @classmethod
    def check_attributes(cls, attributes: Mapping[str, Any]) -> AttributeCheck:
        """The ports' own rules, then the number of literal ``size`` values for the shape."""
        check = super().check_attributes(attributes)
        shape = check.bindings.get("shape", Literal("box"))
        size = check.bindings.get("size")
        if isinstance(shape, Literal) and isinstance(size, Literal):
            problem = size_count_problem(shape.value, list(size.value))
            if problem is not None:
                check.errors.append(
                    (f"bad value for port 'size' of {cls.NODE_ID}: {problem}", None)
                )
        return check

    def step(self) -> Status:
        name = self.get_input("model")
        world = self.world
        if name in world.models:
            try:
                world.spawn_model(name)
            except ValueError as exc:
                raise ActionFailed(str(exc)) from None
            return Status.SUCCESS
        if "shape" not in self.bindings and "size" not in self.bindings:
            known = ", ".join(sorted(world.models)) or "none"
            raise ActionFailed(
                f"no model named '{name}' in {world.path.name}{closest(name, set(world.models))}"
                f"; its models: {known}; for a new primitive give shape, size and pose"
            )
        shape = self.get_input("shape")
        size = list(self.get_input("size"))
        problem = size_count_problem(shape, size)
        if problem is not None:
            raise ActionFailed(problem)
        if not size:
            raise ActionFailed(f"a {shape} needs size=\"{_SIZE_MEANING[shape]}\"")
        dims = {
            "box": lambda: (size[0], size[1], size[2]),
            "cylinder": lambda: (size[0], size[0], size[1]),
            "sphere": lambda: (size[0], size[0], 2 * size[0]),
        }[shape]()
        pose = list(self.get_input("pose"))
        if not pose:
            raise ActionFailed('a new primitive needs pose="x;y;z;yaw" (z of its centre)')
        colour = self.get_input("colour")
        mass = float(self.get_input("mass"))
        half = math.sin(pose[3] / 2), math.cos(pose[3] / 2)
        spec = BodySpec(
            name=name,
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
            world.spawn(spec)
        except ValueError as exc:
            raise ActionFailed(str(exc)) from None
        return Status.SUCCESS


@registry.register
class DeleteModel(RobotAction):
    """Removes a model (movable object or furniture) from the world.

    - SUCCESS when it is gone (it is let go first if attached);
    - FAILURE when there is no such model.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "model": PortInformation(str, True, "name of the model to remove"),
    }

    def step(self) -> Status:
        try:
            self.world.remove(self.get_input("model"))
        except KeyError as exc:
            raise ActionFailed(str(exc.args[0])) from None
        return Status.SUCCESS
