"""Arm moves planned round obstacles: a Sawyer swings its arm from one side to the other past
a post. Without a planner the direct joint move hits the post; with ``planner="auto"`` the move
goes round it (over it), deterministically, and reports its length and samples."""

from __future__ import annotations

from pathlib import Path

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
