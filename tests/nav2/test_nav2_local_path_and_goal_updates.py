"""TruncatePathLocal, GoalUpdater and the smoother, from Nav2's documented behaviour, without
a world (the robot's pose given on the ``pose`` port, goals written to the blackboard)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import bt_manip.nav2  # noqa: F401  (registers the Nav2 nodes)
from bt_manip.bt import Tree, TreeContext, load_tree_string
from bt_manip.clock import ManualClock
from bt_manip.errors import InputError
from bt_manip.nav2.path import Nav2Path
from bt_manip.nav2.smoothing import Smoothed, SmootherOptions, smooth_points


def tree_of(body: str, bb: dict[str, object] | None = None) -> Tree:
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="M">{body}</BehaviorTree></root>'
    return load_tree_string(xml, context=TreeContext(clock=ManualClock()),
                            blackboard=dict(bb or {}))


def line(n: int = 21, step: float = 0.5) -> Nav2Path:
    """Poses along +x every ``step`` metres, heading +x."""
    xs = np.arange(n) * step
    return Nav2Path(np.column_stack([xs, np.zeros(n), np.zeros(n)]), length=xs[-1])


# -- TruncatePathLocal ---------------------------------------------------------------------

def truncate(path: Nav2Path, pose: tuple[float, float, float], **ports: str) -> Nav2Path:
    attrs = " ".join(f'{k}="{v}"' for k, v in ports.items())
    tree = tree_of(f'<TruncatePathLocal input_path="{{path}}" output_path="{{out}}" '
                   f'pose="{{pose}}" {attrs}/>', {"path": path, "pose": pose})
    assert tree.tick().value == "SUCCESS"
    out = tree.blackboard.get("out")
    assert isinstance(out, Nav2Path)
    return out


def test_truncate_path_local_keeps_the_stretch_round_the_nearest_pose() -> None:
    # nearest pose to x=4.1 is x=4.0; back 1.0 m keeps 3.0..4.0, forward 2.0 m keeps ..6.0
    out = truncate(line(), (4.1, 0.3, 0.0), distance_forward="2.0", distance_backward="1.0")
    assert out.poses[:, 0].tolist() == pytest.approx([3.0, 3.5, 4.0, 4.5, 5.0, 5.5, 6.0])
    assert out.length == pytest.approx(3.0)


def test_truncate_path_local_defaults_and_whole_path_ahead() -> None:
    # defaults: 8 m forward, 4 m back
    out = truncate(line(41), (10.0, 0.0, 0.0))
    assert (out.poses[0, 0], out.poses[-1, 0]) == pytest.approx((6.0, 18.0))
    # a negative forward distance keeps everything ahead
    out = truncate(line(41), (10.0, 0.0, 0.0), distance_forward="-1", distance_backward="0")
    assert (out.poses[0, 0], out.poses[-1, 0]) == pytest.approx((10.0, 20.0))


def loop_path() -> Nav2Path:
    """Out along +x to x=2, then back along -x a hand's width to the side (a hairpin)."""
    out = [(x, 0.0, 0.0) for x in np.arange(0.0, 2.01, 0.25)]
    back = [(x, 0.1, math.pi) for x in np.arange(2.0, -0.01, -0.25)]
    return Nav2Path(np.array(out + back), length=4.1)


def test_truncate_path_local_angular_weight_picks_the_leg_the_robot_heads_along() -> None:
    path = loop_path()
    # the robot at x=1, y=0.06 (nearer the return leg) but heading +x: without the weight
    # the return leg's pose is nearest; with it, the outbound one
    near = truncate(path, (1.0, 0.06, 0.0), distance_forward="0", distance_backward="0")
    assert near.poses[:, 2].tolist() == pytest.approx([math.pi])
    weighted = truncate(path, (1.0, 0.06, 0.0), distance_forward="0", distance_backward="0",
                        angular_distance_weight="0.2")
    assert len(weighted) == 1
    assert weighted.poses[0].tolist() == pytest.approx([1.0, 0.0, 0.0])


def test_truncate_path_local_search_distance_follows_the_path_in_order() -> None:
    path = loop_path()
    tree = tree_of('<TruncatePathLocal input_path="{path}" output_path="{out}" pose="{pose}" '
                   'distance_forward="0" distance_backward="0" max_robot_pose_search_dist="0.6"/>',
                   {"path": path, "pose": (0.0, 0.06, 0.0)})
    seen = []
    for x in (0.0, 0.5, 1.0, 1.5):  # along the outbound leg, a little towards the return leg
        tree.blackboard.set("pose", (x, 0.06, 0.0))
        assert tree.tick().value == "SUCCESS"
        seen.append(tuple(tree.blackboard.get("out").poses[0]))
    # the search starts where the last pose was found and looks 0.6 m ahead only: it stays on
    # the outbound leg (heading 0) though the return leg is as near
    assert [s[2] for s in seen] == [0.0, 0.0, 0.0, 0.0]
    assert [s[0] for s in seen] == pytest.approx([0.0, 0.5, 1.0, 1.5])


@pytest.mark.parametrize("written", ["inf", "Infinity", "+INF", " inf "])
def test_truncate_path_local_takes_an_infinite_search_distance_as_leaving_it_out(
        written: str) -> None:
    # as Nav2 reads the port (std::stod): "inf" is no bound, the nearest pose of the whole path
    # is taken, here on the return leg of the hairpin (heading pi), as without the port
    path = loop_path()
    unbounded = truncate(path, (1.0, 0.06, 0.0), distance_forward="0", distance_backward="0")
    given = truncate(path, (1.0, 0.06, 0.0), distance_forward="0", distance_backward="0",
                     max_robot_pose_search_dist=written)
    assert given.poses.tolist() == unbounded.poses.tolist()
    assert given.poses[:, 2].tolist() == pytest.approx([math.pi])
    # the same text read from the blackboard
    tree = tree_of('<TruncatePathLocal input_path="{path}" output_path="{out}" pose="{pose}" '
                   'distance_forward="0" distance_backward="0" '
                   'max_robot_pose_search_dist="{search}"/>',
                   {"path": path, "pose": (1.0, 0.06, 0.0), "search": written})
    assert tree.tick().value == "SUCCESS", tree.root.feedback_message
    assert tree.blackboard.get("out").poses.tolist() == unbounded.poses.tolist()


@pytest.mark.parametrize("written, problem", [
    ("-inf", "must be >= 0 or inf, got -inf"),
    ("nan", "expected a finite number, got 'nan'"),
    ("1e999", "expected a finite number, got '1e999'"),
    ("infinite", "expected a number, got 'infinite'"),
])
def test_truncate_path_local_refuses_other_non_finite_search_distances(
        written: str, problem: str) -> None:
    with pytest.raises(InputError) as refused:
        tree_of(f'<TruncatePathLocal input_path="{{path}}" output_path="{{out}}" '
                f'max_robot_pose_search_dist="{written}"/>')
    assert (f"bad value for port 'max_robot_pose_search_dist' of TruncatePathLocal: {problem}"
            in str(refused.value))


def test_truncate_path_local_fails_without_a_path_or_a_pose() -> None:
    tree = tree_of('<TruncatePathLocal input_path="{path}" output_path="{out}" pose="{pose}"/>',
                   {"path": "not a path", "pose": (0.0, 0.0, 0.0)})
    assert tree.tick().value == "FAILURE"
    assert "Nav2Path" in tree.root.feedback_message
    no_world = tree_of('<TruncatePathLocal input_path="{path}" output_path="{out}"/>',
                       {"path": line()})
    assert no_world.tick().value == "FAILURE"
    assert "needs a world" in no_world.root.feedback_message
    empty = Nav2Path(np.zeros((0, 3)))
    tree = tree_of('<TruncatePathLocal input_path="{path}" output_path="{out}" pose="{pose}"/>',
                   {"path": empty, "pose": (0.0, 0.0, 0.0)})
    assert tree.tick().value == "SUCCESS"
    assert len(tree.blackboard.get("out")) == 0


# -- GoalUpdater ---------------------------------------------------------------------------

def test_goal_updater_passes_the_goal_until_an_update_arrives() -> None:
    tree = tree_of('<GoalUpdater input_goal="{goal}" output_goal="{current}">'
                   '<AlwaysSuccess/></GoalUpdater>', {"goal": "1;2;0"})
    assert tree.tick().value == "SUCCESS"
    assert tree.blackboard.get("current") == "1;2;0"
    tree.blackboard.set("@goal_update", "5;6;1")  # a goal sent on the topic
    assert tree.tick().value == "SUCCESS"
    assert tree.blackboard.get("current") == "5;6;1"
    assert tree.tick().value == "SUCCESS"  # the last goal received stays in effect
    assert tree.blackboard.get("current") == "5;6;1"
    tree.blackboard.set("goal", "7;8;0")  # the input goal is now the newer one
    tree.tick()
    assert tree.blackboard.get("current") == "7;8;0"


def test_goal_updater_returns_its_childs_status_and_updates_goals() -> None:
    tree = tree_of('<GoalUpdater input_goals="{goals}" output_goals="{current}">'
                   '<AlwaysFailure/></GoalUpdater>', {"goals": "1;2;0|3;4;0"})
    assert tree.tick().value == "FAILURE"
    assert tree.blackboard.get("current") == "1;2;0|3;4;0"
    tree.blackboard.set("goals_update", "9;9;0")
    tree.tick()
    assert tree.blackboard.get("current") == "9;9;0"


# -- the smoother --------------------------------------------------------------------------

FREE = np.ones((100, 100))  # a 5 m x 5 m grid of free cells at 0.05 m, origin (0, 0)


def corner(n: int = 20) -> np.ndarray:
    """An L: along +x from (0.5, 0.5) to (2.5, 0.5), then along +y to (2.5, 2.5)."""
    a = np.linspace(0.5, 2.5, n + 1)
    return np.vstack([np.column_stack([a, np.full_like(a, 0.5)]),
                      np.column_stack([np.full(n, 2.5), a[1:]])])


def turn_angles(pts: np.ndarray) -> np.ndarray:
    d = np.diff(pts, axis=0)
    h = np.arctan2(d[:, 1], d[:, 0])
    return np.abs(np.remainder(np.diff(h) + math.pi, math.tau) - math.pi)


def test_smoother_rounds_a_corner_and_keeps_the_ends() -> None:
    pts = corner()
    out, outcome = smooth_points(pts, FREE, (0.0, 0.0), 0.05)
    assert out.shape == pts.shape
    assert out[0].tolist() == pts[0].tolist() and out[-1].tolist() == pts[-1].tolist()
    assert turn_angles(pts).max() == pytest.approx(math.pi / 2)
    assert turn_angles(out).max() < math.pi / 4  # the right angle spread over the bend
    assert outcome in (Smoothed.CONVERGED, Smoothed.SWEEPS_USED)
    straight = np.column_stack([np.linspace(0.5, 4.0, 30), np.full(30, 1.0)])
    flat, done = smooth_points(straight, FREE, (0.0, 0.0), 0.05)
    assert done is Smoothed.CONVERGED
    assert np.allclose(flat, straight)


def test_smoother_never_moves_a_point_into_a_lethal_cell() -> None:
    cost = FREE.copy()
    cost[:25, 40:] = np.inf  # lethal inside the corner: x >= 2.0, y < 1.25
    pts = corner()
    free_before = ~np.isinf(cost[(pts[:, 1] / 0.05).astype(int), (pts[:, 0] / 0.05).astype(int)])
    out, _ = smooth_points(pts, cost, (0.0, 0.0), 0.05, SmootherOptions(max_sweeps=200))
    rows, cols = (out[:, 1] / 0.05).astype(int), (out[:, 0] / 0.05).astype(int)
    assert not np.isinf(cost[rows, cols])[free_before].any()


def test_goal_updater_in_a_subtree_hears_the_root_topic() -> None:
    xml = ('<root BTCPP_format="4" main_tree_to_execute="M">'
           '<BehaviorTree ID="M"><SubTree ID="Nav" goal="{goal}" current="{current}"/>'
           '</BehaviorTree>'
           '<BehaviorTree ID="Nav"><GoalUpdater input_goal="{goal}" output_goal="{current}">'
           '<AlwaysSuccess/></GoalUpdater></BehaviorTree></root>')
    tree = load_tree_string(xml, context=TreeContext(clock=ManualClock()),
                            blackboard={"goal": "1;2;0"})
    tree.tick()
    assert tree.blackboard.get("current") == "1;2;0"
    tree.blackboard.set("goal_update", "4;4;0")
    tree.tick()
    assert tree.blackboard.get("current") == "4;4;0"
