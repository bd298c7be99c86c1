"""Helpers and fixtures of the behaviour tests: worlds with the robot placed (placing is test
setup, not an action), and a way to run a snippet of tree XML against a world."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TypeVar

import pytest

import bt_manip.behaviours  # noqa: F401  (registers the robot nodes)
from bt_manip.bt import Tree, load_tree_string
from bt_manip.run.context import RunContext
from bt_manip.run.report import RunReport
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.world import World

ROOT = Path(__file__).resolve().parents[2]


def place_robot(world: World, name: str, x: float, y: float, yaw: float) -> None:
    world.robots[name].reset_base_pose(x, y, yaw)
    world.step(24)


def run_xml(world: World, body: str, max_sim_time: float = 60.0) -> tuple[RunReport, Tree]:
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'
    tree = load_tree_string(xml, context=RunContext.for_world(world))
    return Runner(tree, world, RunOptions(max_sim_time=max_sim_time)).run(), tree


T = TypeVar("T")


def sample_every_step(world: World, probe: Callable[[], T]) -> list[T]:
    """A list that receives ``probe()`` after every physics step of ``world`` from now on.

    Tests assert on extremes of this list, not on 20 Hz tick samples: a peak can fall between
    two ticks, and where it falls depends on the machine's floating-point path.
    """
    samples: list[T] = []
    step = world.step

    def stepping(n: int = 1) -> None:
        for _ in range(n):
            step(1)
            samples.append(probe())

    world.step = stepping  # type: ignore[method-assign]
    return samples


def reasons(report: RunReport) -> dict[str, str]:
    return {n.path.split("/")[-1]: n.reason for n in report.nodes if n.reason}


@pytest.fixture
def house_at_pregrasp() -> Iterator[World]:
    with World(ROOT / "worlds" / "tb3_house.yaml", seed=0) as world:
        p = world.poses["pregrasp_panel"]
        place_robot(world, "husky", p.x, p.y, p.yaw)
        yield world


@pytest.fixture
def table() -> Iterator[World]:
    with World(ROOT / "worlds" / "sawyer_table.yaml", seed=0) as world:
        yield world
