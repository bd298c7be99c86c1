"""What the World announces: bodies spawned and deleted (by the tree or a fault), attach and
detach, each once, after the change, with the sim time."""

from __future__ import annotations

from pathlib import Path

import pybullet as pb
import pytest

import bt_manip.behaviours  # noqa: F401  (registers the robot nodes)
from bt_manip.bt import load_tree_string
from bt_manip.run.context import RunContext
from bt_manip.run.faults import FaultInjector, FaultSpec
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.events import Attached, BodyAdded, BodyRemoved, Detached, WorldEvent
from bt_manip.sim.world import World
from bt_manip.sim.world_spec import BodySpec, Part, Pose3D, Range2D

ROOT = Path(__file__).resolve().parents[2]
HOUSE = ROOT / "worlds" / "tb3_house.yaml"
TABLE = ROOT / "worlds" / "sawyer_table.yaml"


def _listen(world: World) -> list[WorldEvent]:
    heard: list[WorldEvent] = []
    world.events.subscribe(heard.append)
    return heard


def _crate(name: str, xyz: tuple[float, float, float]) -> BodySpec:
    return BodySpec(
        name=name, movable=True, parts=[Part("box", (0.1, 0.1, 0.1))], urdf=None,
        pose=Pose3D(xyz), planar=False, mass=1.0, friction=0.8, colour=(0.5, 0.3, 0.1, 1.0),
        randomize=Range2D(), line=0,
    )


def test_spawn_and_delete_are_announced_with_the_body() -> None:
    with World(TABLE, seed=0) as world:
        heard = _listen(world)
        world.step(12)
        block = world.spawn_model("block_3")
        world.step(12)
        world.remove("block_3")
        added, removed = heard
        assert isinstance(added, BodyAdded) and isinstance(removed, BodyRemoved)
        assert (added.name, added.body_id, added.kind) == ("block_3", block, "object")
        assert added.spec is world.models["block_3"]
        assert added.time == pytest.approx(12 / world.rate_hz)
        assert (removed.name, removed.body_id, removed.kind) == ("block_3", block, "object")
        assert removed.time == pytest.approx(24 / world.rate_hz)


def test_a_refused_spawn_announces_nothing_and_leaves_no_body() -> None:
    with World(TABLE, seed=0) as world:
        heard = _listen(world)
        bodies = pb.getNumBodies(physicsClientId=world.client)
        with pytest.raises(ValueError, match=r"would start .* inside 'cafe_table'"):
            world.spawn(_crate("stuck", (1.0, 0.0, 0.72)))
        assert heard == []
        assert pb.getNumBodies(physicsClientId=world.client) == bodies
        assert "stuck" not in world.infos


def test_unsubscribed_listeners_hear_nothing_more() -> None:
    with World(TABLE, seed=0) as world:
        heard: list[WorldEvent] = []
        stop = world.events.subscribe(heard.append)
        world.spawn_model("block_0")
        stop()
        world.spawn_model("block_1")
        assert [e.name for e in heard if isinstance(e, BodyAdded)] == ["block_0"]
        assert len(world.events) == 0


def _grasp_panel(world: World) -> str:
    """Place the Husky at the panel's pre-grasp pose, grasp and attach it; the run's result."""
    p = world.poses["pregrasp_panel"]
    world.robots["husky"].reset_base_pose(p.x, p.y, p.yaw)
    world.step(24)
    xml = (
        '<root BTCPP_format="4"><BehaviorTree ID="M"><Sequence><OpenGripper/>'
        '<MoveJointsSequentially targets="70;11;78;-56;85;4" order="0;2;3;5;4;1"/>'
        '<CloseGripper/><Attach object="panel"/></Sequence></BehaviorTree></root>'
    )
    tree = load_tree_string(xml, context=RunContext.for_world(world))
    report = Runner(tree, world, RunOptions(max_sim_time=30)).run()
    return report.status + " " + report.reason


def test_attach_detach_and_deleting_a_held_object() -> None:
    with World(HOUSE, seed=0) as world:
        heard = _listen(world)
        assert _grasp_panel(world).startswith("SUCCESS")
        _check_attach_events(world, heard)


def _check_attach_events(world: World, heard: list[WorldEvent]) -> None:
    (attached,) = heard
    assert isinstance(attached, Attached)
    assert (attached.object_name, attached.robot_name) == ("panel", "husky")
    assert attached.link_name == world.robots["husky"].description.end_effector
    assert world.attachments.detach("panel").ok
    assert world.attachments.attach("husky", "panel").ok
    world.remove("panel")  # let go first, then gone
    assert [type(e) for e in heard] == [Attached, Detached, Attached, Detached, BodyRemoved]
    assert all(e.object_name == "panel" for e in heard[:4])  # type: ignore[union-attr]
    assert heard[3].robot_name == "husky"  # type: ignore[union-attr]
    assert heard[4].name == "panel"  # type: ignore[union-attr]


def test_the_block_fault_announces_its_crate() -> None:
    with World(HOUSE, seed=0) as world:
        heard = _listen(world)
        faults = FaultInjector([FaultSpec("block", 1.0)], seed=0, clock=world.clock)
        xml = (
            '<root BTCPP_format="4"><BehaviorTree ID="M"><Navigate goal="goal"/>'
            "</BehaviorTree></root>"
        )
        context = RunContext.for_world(world, faults=faults)
        tree = load_tree_string(xml, context=context)
        for _ in range(40):
            tree.tick()
            world.step(12)
            if heard:
                break
        tree.halt()
        (crate,) = heard
        assert isinstance(crate, BodyAdded)
        assert crate.name == "dropped_crate_0" and crate.kind == "object"
        assert crate.body_id == world.movable["dropped_crate_0"]
        assert crate.spec.parts[0].shape == "box"
