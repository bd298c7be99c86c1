"""Arm moves planned round obstacles: a Sawyer swings its arm from one side to the other past
a post. Without a planner the direct joint move hits the post; with ``planner="auto"`` the move
goes round it (over it), deterministically, and reports its length and samples."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_manip.episode import Episode, EpisodeSpec

WORLD = """name: sawyer_post
robots:
  - {name: sawyer, description: sawyer, pose: [0.0, 0.0, 0.0], arm_state: home}
furniture:
  - name: post
    colour: dark_grey
    pose: {xyz: [0.75, 0.0, 0.6]}
    parts:
      - {shape: box, size: [0.1, 0.1, 1.2]}
"""
LEFT = "50;0;0;0;0;33;190"
RIGHT = "-50;0;0;0;0;33;190"


def _run(tmp_path: Path, planner: str, goal: str = RIGHT, seed: int = 0,
         check: str = "") -> tuple[str, str, tuple[float, ...]]:
    tmp_path.mkdir(exist_ok=True)
    (tmp_path / "world.yaml").write_text(WORLD)
    (tmp_path / "tree.xml").write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>\n'
        f'  <MoveJoints name="left" targets="{LEFT}"/>\n'
        f'  <MoveJoints name="right" targets="{goal}" planner="{planner}" '
        'path_length="{length}" plan_samples="{samples}"/>\n'
        + (f'  <ScriptCondition name="check" code="{check}"/>\n' if check else "")
        + "</Sequence></BehaviorTree></root>\n"
    )
    spec = EpisodeSpec(tree=str(tmp_path / "tree.xml"), world=str(tmp_path / "world.yaml"),
                       seed=seed)
    with Episode(spec) as episode:
        report = episode.run()
        assert episode.world is not None
        q = tuple(round(float(v), 9) for v in episode.world.robots["sawyer"].arm_positions())
        return str(report.status), report.reason, q


def test_direct_move_hits_the_post(tmp_path: Path) -> None:
    status, reason, _ = _run(tmp_path, "none")
    assert status == "FAILURE" and "touched 'post'" in reason


def test_planned_move_goes_round_the_post(tmp_path: Path) -> None:
    # the direct move is 100 deg of joint 0 (1.745 rad): the planned one is longer
    status, reason, _ = _run(tmp_path, "auto", check="samples &gt; 0 &amp;&amp; length &gt; 1.75")
    assert status == "SUCCESS", reason


def test_free_direct_move_is_not_planned(tmp_path: Path) -> None:
    status, reason, _ = _run(tmp_path, "auto", goal="30;0;0;0;0;33;190",
                             check="samples == 0 &amp;&amp; length &lt; 0.35")
    assert status == "SUCCESS", reason


def test_goal_inside_the_post_fails_with_the_reason(tmp_path: Path) -> None:
    status, reason, _ = _run(tmp_path, "rrtconnect", goal="0;0;0;0;0;33;190")
    assert status == "FAILURE"
    assert "planning the arm's move: the goal is in collision" in reason
    assert "post" in reason


@pytest.mark.parametrize("seed", [0, 1])
def test_same_seed_same_motion(tmp_path: Path, seed: int) -> None:
    assert _run(tmp_path / "a", "auto", seed=seed) == _run(tmp_path / "b", "auto", seed=seed)


def test_a_planned_move_keeps_within_the_joint_speed_limits(tmp_path: Path) -> None:
    """The planned path is timed within each joint's velocity (and acceleration) limits; the
    arm follows it at no more than the speed asked, with the tracking margin, at every step."""
    from bhelpers import run_xml, sample_every_step

    from bt_manip.behaviours.arm import TRACK_MARGIN
    from bt_manip.sim.world import World

    (tmp_path / "world.yaml").write_text(WORLD)
    with World(tmp_path / "world.yaml", seed=0) as world:
        robot = world.robots["sawyer"]
        report, _ = run_xml(world, f'<MoveJoints targets="{LEFT}"/>')
        assert report.status == "SUCCESS"
        speeds = sample_every_step(world, lambda: robot.arm_motion()[1])
        report, tree = run_xml(world, f'<MoveJoints targets="{RIGHT}" speed="0.5" '
                                      'plan_samples="{n}"/>')
        assert report.status == "SUCCESS", report.reason
        assert tree.blackboard.as_dict()["n"] > 0
        limits = [0.5 * v * TRACK_MARGIN for v in robot.description.arm.velocity_limits]
        peak = [max(abs(s[j]) for s in speeds) for j in range(len(limits))]
        assert all(p <= lim * 1.05 for p, lim in zip(peak, limits, strict=True)), (peak, limits)
        assert max(peak) > 0.1  # it did move


def test_a_plan_is_drawn_and_its_wall_time_reported(tmp_path: Path) -> None:
    from bhelpers import ROOT
    from jsonschema import validate

    (tmp_path / "world.yaml").write_text(WORLD)
    (tmp_path / "tree.xml").write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>\n'
        f'  <MoveJoints name="left" targets="{LEFT}"/>\n'
        f'  <MoveJoints name="right" targets="{RIGHT}"/>\n'
        "</Sequence></BehaviorTree></root>\n")
    spec = EpisodeSpec(tree=str(tmp_path / "tree.xml"), world=str(tmp_path / "world.yaml"))
    with Episode(spec) as episode:
        report = episode.run()
        assert report.status == "SUCCESS", report.reason
        planning = report.extra["arm_planning"]["sawyer"]
        assert planning["plans"] == 1 and planning["samples"] > 0
        assert planning["wall_time_s"] > 0
        drawn = episode.context.overlay.items["arm_plan"]
        assert episode.world is not None
        robot = episode.world.robots["sawyer"]
        # the drawn path ends where the grasp frame ended up (within the arm's tolerance)
        end = robot.link_transform(robot.description.grasp_frame)[:3, 3]
        assert np.linalg.norm(drawn.points[-1] - end) < 0.03
        assert len(drawn.points) > 10
    import json
    schema = json.loads((ROOT / "docs" / "schemas" / "run-report.schema.json").read_text())
    validate(report.to_json(), schema)
