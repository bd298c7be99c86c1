"""World operations for trees: add and remove models while the task runs."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction
from bt_manip.bt import registry
from bt_manip.bt.node import AttributeCheck, closest
from bt_manip.bt.ports import Literal
from bt_manip.sim.world_spec import COLOURS, BodySpec, Part, Pose3D, Range2D

SHAPE_SIZES = {"box": 3, "cylinder": 2, "sphere": 1}
"""How many ``size`` values each primitive takes."""
_SIZE_MEANING = {"box": "x;y;z extents", "cylinder": "radius;height", "sphere": "radius"}


def _finite(values: list[float]) -> bool:
    return all(math.isfinite(v) for v in values)


def spawn_value_problem(port: str, value: Any, shape: str | None) -> str | None:
    """What is wrong with ``value`` for SpawnModel's ``port`` (None if nothing); ``shape`` is
    the primitive's shape when known (for the number of ``size`` values)."""
    if port == "model" and not str(value).strip():
        return "model needs a name"
    if port == "shape" and value not in SHAPE_SIZES:
        return f"shape must be box, cylinder or sphere, got '{value}'"
    if port == "size" and value:
        size = list(value)
        need = SHAPE_SIZES.get(shape or "")
        if need is not None and len(size) != need:
            return (f"a {shape} takes {need} size value{'s' if need > 1 else ''} "
                    f"({_SIZE_MEANING[shape or '']}), got {len(size)}: {size}")
        if not _finite(size) or any(v <= 0 for v in size):
            return f"size values must be positive finite metres, got {size}"
    if port == "pose" and value:
        pose = list(value)
        if len(pose) != 4 or not _finite(pose):
            return f"pose takes 4 finite numbers x;y;z;yaw, got {pose}"
    if port in ("mass", "friction"):
        number = float(value)
        if not math.isfinite(number) or number < 0:
            what = "kg, 0 for a static model" if port == "mass" else "a coefficient"
            return f"{port} must be a finite number >= 0 ({what}), got {value}"
    if port == "colour" and value not in COLOURS:
        return f"unknown colour '{value}'; known: {', '.join(sorted(COLOURS))}"
    return None


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

    @classmethod
    def check_attributes(cls, attributes: Mapping[str, Any]) -> AttributeCheck:
        """The ports' own checks, then the range of every literal value."""
        check = super().check_attributes(attributes)
        shape_binding = check.bindings.get("shape", Literal("box"))
        shape = shape_binding.value if isinstance(shape_binding, Literal) else None
        for port, binding in check.bindings.items():
            if isinstance(binding, Literal):
                problem = spawn_value_problem(port, binding.value, shape)
                if problem is not None:
                    check.errors.append(
                        (f"bad value for port '{port}' of {cls.NODE_ID}: {problem}", None)
                    )
        return check

    def _input(self, port: str, shape: str | None = None) -> Any:
        value = self.get_input(port)
        problem = spawn_value_problem(port, value, shape)
        if problem is not None:
            raise ActionFailed(problem)
        return value

    def step(self) -> Status:
        name = self._input("model")
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
        shape = self._input("shape")
        size = list(self._input("size", shape))
        if not size:
            raise ActionFailed(f"a {shape} needs size=\"{_SIZE_MEANING[shape]}\"")
        dims = {
            "box": lambda: (size[0], size[1], size[2]),
            "cylinder": lambda: (size[0], size[0], size[1]),
            "sphere": lambda: (size[0], size[0], 2 * size[0]),
        }[shape]()
        pose = list(self._input("pose"))
        if not pose:
            raise ActionFailed('a new primitive needs pose="x;y;z;yaw" (z of its centre)')
        colour = self._input("colour")
        mass = float(self._input("mass"))
        half = math.sin(pose[3] / 2), math.cos(pose[3] / 2)
        spec = BodySpec(
            name=name,
            movable=mass > 0,
            parts=[Part(shape, dims, colour=COLOURS[colour])],
            urdf=None,
            pose=Pose3D((pose[0], pose[1], pose[2]), (0.0, 0.0, half[0], half[1])),
            planar=False,
            mass=mass,
            friction=float(self._input("friction")),
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

    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        "model": PortInformation(str, True, "name of the model to remove"),
    }

    def step(self) -> Status:
        try:
            self.world.remove(self.get_input("model"))
        except KeyError as exc:
            raise ActionFailed(str(exc.args[0])) from None
        return Status.SUCCESS
