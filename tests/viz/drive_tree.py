"""A small py_trees tree that drives the Husky of ``viz_room.yaml``, for the viewer tests."""

from __future__ import annotations

from typing import Any

import py_trees
from py_trees.common import Status

from bt_manip.overlay import Overlay
from bt_manip.run.context import RunContext

HERE = __import__("pathlib").Path(__file__).resolve().parent
ROOM = HERE / "viz_room.yaml"


class Drive(py_trees.behaviour.Behaviour):
    """RUNNING while the base drives at (v, w) for ``duration`` s of sim; then SUCCESS.

    On start it shows its planned path and a target frame on the run's overlay.
    """

    def __init__(
        self, name: str, world: Any, overlay: Overlay, duration: float, v: float, w: float
    ) -> None:
        super().__init__(name)
        self.world, self.overlay, self.duration, self.v, self.w = world, overlay, duration, v, w
        self.t0 = 0.0

    def initialise(self) -> None:
        self.t0 = self.world.time
        x, y, _ = self.world.robots["husky"].base_pose2d()
        overlay = self.overlay
        overlay.show_path(f"{self.name}_plan", [(x, y), (x + 0.8, y), (x + 1.4, y + 0.4)])
        target = __import__("numpy").eye(4)
        target[:3, 3] = (x + 1.4, y + 0.4, 0.5)
        overlay.show_frame("target", target)
        self.feedback_message = ""

    def update(self) -> Status:
        robot = self.world.robots["husky"]
        if self.world.time - self.t0 >= self.duration - 1e-9:
            robot.stop_base()
            self.feedback_message = "arrived"
            return Status.SUCCESS
        robot.set_base_twist(self.v, self.w)
        self.feedback_message = "driving"
        return Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID:
            self.world.robots["husky"].stop_base()


class Fail(py_trees.behaviour.Behaviour):
    """FAILURE at once, with a reason."""

    def update(self) -> Status:
        self.feedback_message = "no path to the goal: the doorway is blocked"
        return Status.FAILURE


class DriveTree:
    """drive (v=0.6) -> turn -> a fallback whose first child fails, then a short wait."""

    def __init__(self, world: Any, drive_s: float = 2.0, turn_s: float = 1.5) -> None:
        self.context = RunContext.for_world(world)  # viewers draw its overlay
        overlay = self.context.overlay
        self.root = py_trees.composites.Sequence(
            "mission",
            memory=True,
            children=[
                Drive("drive", world, overlay, drive_s, 0.6, 0.0),
                Drive("turn", world, overlay, turn_s, 0.2, 0.8),
                py_trees.composites.Selector(
                    "recover",
                    memory=True,
                    children=[Fail("plan_a"), Drive("plan_b", world, overlay, 0.5, 0.0, 0.0)],
                ),
            ],
        )

    def tick(self) -> Status:
        self.root.tick_once()
        return self.root.status

    def halt(self) -> None:
        self.root.stop(Status.INVALID)
