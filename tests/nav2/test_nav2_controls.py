"""Nav2's controls and decorators tick by tick, with scripted children on a manual clock."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any, ClassVar

import numpy as np
import pytest
from py_trees.common import Status
from py_trees.ports import PortInformation

import bt_manip.nav2  # noqa: F401  (registers the Nav2 nodes)
from bt_manip.bt import ActionNode, Tree, TreeContext, load_tree_string, registry
from bt_manip.clock import ManualClock
from bt_manip.errors import InputError
from bt_manip.nav2.path import Nav2Path

SCRIPTS: dict[str, list[str]] = {}
"""Per scripted child: the statuses it returns, one per tick (the last one repeats)."""
LOG: list[tuple[str, str]] = []
"""(event, child) in order: "tick" for each tick, "halt" when halted while RUNNING."""


class Scripted(ActionNode):
    """Returns the next status of ``SCRIPTS[id]`` at each tick; logs ticks and halts."""

    STATEFUL = False
    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        "id": PortInformation(str, True, "script name"),
    }

    def update(self) -> Status:
        key = self.get_input("id")
        LOG.append(("tick", key))
        script = SCRIPTS[key]
        value = script.pop(0) if len(script) > 1 else script[0]
        return {"S": Status.SUCCESS, "F": Status.FAILURE, "R": Status.RUNNING}[value]

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID:
            LOG.append(("halt", self.get_input("id")))


@pytest.fixture(autouse=True)
def scripted() -> Iterator[None]:
    registry.register(Scripted)
    SCRIPTS.clear()
    LOG.clear()
    yield
    registry.unregister("Scripted")


def make(body: str, scripts: dict[str, str]) -> tuple[Tree, ManualClock]:
    for key, statuses in scripts.items():
        SCRIPTS[key] = list(statuses)
    clock = ManualClock()
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'
    return load_tree_string(xml, context=TreeContext(clock=clock)), clock


def tick(tree: Tree) -> tuple[str, list[tuple[str, str]]]:
    """Tick once: the root's status and what the children did in that tick."""
    LOG.clear()
    return tree.tick().value, list(LOG)


def kid(key: str) -> str:
    return f'<Scripted id="{key}"/>'


def test_pipeline_sequence_keeps_ticking_the_children_it_reached() -> None:
    tree, _ = make(f"<PipelineSequence>{kid('a')}{kid('b')}{kid('c')}</PipelineSequence>",
                   {"a": "RSR", "b": "RRS", "c": "RS"})
    assert tick(tree) == ("RUNNING", [("tick", "a")])
    assert tick(tree) == ("RUNNING", [("tick", "a"), ("tick", "b")])
    # a is RUNNING again but lies before b, the furthest child reached: b is ticked too
    assert tick(tree) == ("RUNNING", [("tick", "a"), ("tick", "b")])
    assert tick(tree) == ("RUNNING", [("tick", "a"), ("tick", "b"), ("tick", "c")])
    # c succeeds: every child is halted (a was RUNNING) and the sequence succeeds
    assert tick(tree) == (
        "SUCCESS", [("tick", "a"), ("tick", "b"), ("tick", "c"), ("halt", "a")]
    )


def test_pipeline_sequence_halts_everything_on_a_failure() -> None:
    tree, _ = make(f"<PipelineSequence>{kid('a')}{kid('b')}</PipelineSequence>",
                   {"a": "SR", "b": "RF"})
    assert tick(tree)[0] == "RUNNING"
    assert tick(tree) == ("FAILURE", [("tick", "a"), ("tick", "b"), ("halt", "a")])
    # starts over from the first child
    SCRIPTS["a"] = ["R"]
    assert tick(tree) == ("RUNNING", [("tick", "a")])


def test_recovery_node_retries_after_a_successful_recovery() -> None:
    tree, _ = make(
        f'<RecoveryNode number_of_retries="2">{kid("work")}{kid("fix")}</RecoveryNode>',
        {"work": "FFRS", "fix": "RSRS"},
    )
    # work fails: the recovery runs in the same tick
    assert tick(tree) == ("RUNNING", [("tick", "work"), ("tick", "fix")])
    # recovery succeeds: work again in the same tick, fails again, recovery at once
    assert tick(tree) == ("RUNNING", [("tick", "fix"), ("tick", "work"), ("tick", "fix")])
    # second recovery succeeds (two retries allowed): work again
    assert tick(tree) == ("RUNNING", [("tick", "fix"), ("tick", "work")])
    assert tick(tree) == ("SUCCESS", [("tick", "work")])


def test_recovery_node_fails_when_retries_are_spent_or_the_recovery_fails() -> None:
    tree, _ = make(f"<RecoveryNode>{kid('work')}{kid('fix')}</RecoveryNode>",
                   {"work": "F", "fix": "S"})
    # default: one retry -> work, fix, work, then FAILURE
    assert tick(tree) == ("FAILURE", [("tick", "work"), ("tick", "fix"), ("tick", "work")])
    # the count was reset: the same again
    assert tick(tree) == ("FAILURE", [("tick", "work"), ("tick", "fix"), ("tick", "work")])
    tree, _ = make(f"<RecoveryNode>{kid('w2')}{kid('f2')}</RecoveryNode>",
                   {"w2": "F", "f2": "F"})
    assert tick(tree) == ("FAILURE", [("tick", "w2"), ("tick", "f2")])


def test_recovery_node_without_a_limit_retries_until_work_succeeds() -> None:
    # Nav2's recovery-manager trees write number_of_retries="-1": no limit
    tree, _ = make(
        f'<RecoveryNode number_of_retries="-1">{kid("work")}{kid("fix")}</RecoveryNode>',
        {"work": "F" * 5 + "S", "fix": "S"},
    )
    status, ticks = tick(tree)
    assert status == "SUCCESS"
    assert ticks == [("tick", "work"), ("tick", "fix")] * 5 + [("tick", "work")]
    # children that fail and recover at once forever: the tick still ends, RUNNING
    from bt_manip.nav2.controls import RecoveryNode

    tree, _ = make(
        f'<RecoveryNode number_of_retries="-1">{kid("w3")}{kid("f3")}</RecoveryNode>',
        {"w3": "F" * 1000, "f3": "S" * 1000},
    )
    status, ticks = tick(tree)
    assert status == "RUNNING"
    assert ticks.count(("tick", "f3")) == RecoveryNode.RETRIES_PER_TICK
    with pytest.raises(InputError, match="must be >= 0 or -1, got -2"):
        make(f'<RecoveryNode number_of_retries="-2">{kid("w4")}{kid("f4")}</RecoveryNode>',
             {"w4": "F", "f4": "S"})


def test_round_robin_takes_turns_across_activations() -> None:
    tree, _ = make(f"<RoundRobin>{kid('a')}{kid('b')}{kid('c')}</RoundRobin>",
                   {"a": "S", "b": "RS", "c": "FS"})
    assert tick(tree) == ("SUCCESS", [("tick", "a")])
    assert tick(tree) == ("RUNNING", [("tick", "b")])
    assert tick(tree) == ("SUCCESS", [("tick", "b")])
    # c fails: the next child (a) is tried within the same tick
    assert tick(tree) == ("SUCCESS", [("tick", "c"), ("tick", "a")])
    assert tick(tree) == ("SUCCESS", [("tick", "b")])


def test_round_robin_fails_when_every_child_fails_in_turn() -> None:
    tree, _ = make(f"<RoundRobin>{kid('a')}{kid('b')}</RoundRobin>", {"a": "F", "b": "F"})
    assert tick(tree) == ("FAILURE", [("tick", "a"), ("tick", "b")])
    assert tick(tree) == ("FAILURE", [("tick", "a"), ("tick", "b")])


def test_rate_controller_ticks_its_child_at_the_rate() -> None:
    """In a PipelineSequence, as in Nav2's trees: the planner at 2 Hz, the controller always."""
    tree, clock = make(
        f'<PipelineSequence><RateController hz="2.0">{kid("plan")}</RateController>'
        f'{kid("drive")}</PipelineSequence>',
        {"plan": "S", "drive": "R"},
    )
    ticked_at = []
    for _ in range(12):
        status, log = tick(tree)
        assert status == "RUNNING"
        assert log[-1] == ("tick", "drive")
        if ("tick", "plan") in log:
            ticked_at.append(round(clock.now(), 2))
        clock.advance(0.1)
    assert ticked_at == [0.0, 0.5, 1.0]


def test_rate_controller_keeps_ticking_a_running_child() -> None:
    tree, clock = make(
        f'<PipelineSequence><RateController hz="1.0">{kid("plan")}</RateController>'
        f'{kid("drive")}</PipelineSequence>',
        {"plan": "RRS", "drive": "R"},
    )
    ran = []
    for _ in range(4):
        _, log = tick(tree)
        ran.append(("tick", "plan") in log)
        clock.advance(0.1)
    # RUNNING, RUNNING, SUCCESS (then drive), then not due for a second
    assert ran == [True, True, True, False]


def test_error_code_conditions() -> None:
    body = (
        '<Sequence><WouldAPlannerRecoveryHelp error_code="{plan}"/>'
        '<WouldAControllerRecoveryHelp error_code="{follow}"/>'
        '<AreErrorCodesPresent error_code="{other}" error_codes_to_check="701,703"/>'
        '<WouldASmootherRecoveryHelp error_code="{smooth}"/>'
        "</Sequence>"
    )
    cases: list[tuple[dict[str, Any], str]] = [
        ({"plan": 208, "follow": 105, "other": 703, "smooth": 504}, "SUCCESS"),
        ({"plan": 200, "follow": 106, "other": 701, "smooth": 503}, "SUCCESS"),
        ({"plan": 206, "follow": 105, "other": 703, "smooth": 500}, "FAILURE"),  # goal occupied
        ({"plan": 207, "follow": 103, "other": 703, "smooth": 502}, "FAILURE"),  # invalid path
        ({"plan": 207, "follow": 104, "other": 700, "smooth": 502}, "FAILURE"),
        ({"plan": 207, "follow": 104, "other": 701, "smooth": 505}, "FAILURE"),  # invalid path
    ]
    for values, expected in cases:
        tree = load_tree_string(
            f'<root BTCPP_format="4"><BehaviorTree ID="M">{body}</BehaviorTree></root>',
            blackboard=dict(values),
        )
        assert tree.tick().value == expected, values


def test_goal_updated_reports_a_new_goal_once() -> None:
    tree = load_tree_string(
        '<root BTCPP_format="4"><BehaviorTree ID="M"><GoalUpdated/></BehaviorTree></root>',
        blackboard={"goal": "1;2;0"},
    )
    node = tree.root  # ticked without a parent resetting it in between
    assert node.execute_tick().value == "FAILURE"  # inactive: records the goal
    assert node.execute_tick().value == "FAILURE"  # same goal
    tree.blackboard.set("goal", "3;2;0")
    assert node.execute_tick().value == "SUCCESS"  # changed
    assert node.execute_tick().value == "FAILURE"  # recorded
    tree.blackboard.set("goal", "5;2;0")
    node.reset_status()  # a parent reset it: it records the goal again
    assert node.execute_tick().value == "FAILURE"


def test_single_trigger_runs_its_child_once_until_reset() -> None:
    tree, _ = make(f"<SingleTrigger>{kid('once')}</SingleTrigger>", {"once": "RS"})
    node = tree.root  # ticked without a parent resetting it in between
    LOG.clear()
    assert node.execute_tick().value == "RUNNING"
    assert node.execute_tick().value == "SUCCESS"
    assert node.execute_tick().value == "FAILURE"  # not again
    assert LOG == [("tick", "once"), ("tick", "once")]
    node.reset_status()
    assert node.execute_tick().value == "SUCCESS"  # reset: once more


def test_time_expired_succeeds_once_per_period() -> None:
    clock = ManualClock()
    tree = load_tree_string(
        '<root BTCPP_format="4"><BehaviorTree ID="M"><TimeExpired seconds="1"/></BehaviorTree>'
        "</root>",
        context=TreeContext(clock=clock),
    )
    node = tree.root
    seen = []
    for dt in (0.0, 0.5, 0.6, 0.1, 0.95):
        clock.advance(dt)
        seen.append(node.execute_tick().value)
    assert seen == ["FAILURE", "FAILURE", "SUCCESS", "FAILURE", "SUCCESS"]


def test_goal_updated_controller_ticks_its_child_when_the_goal_changes() -> None:
    tree, _ = make(
        f"<PipelineSequence><GoalUpdatedController>{kid('plan')}</GoalUpdatedController>"
        f"{kid('drive')}</PipelineSequence>",
        {"plan": "S", "drive": "R"},
    )
    tree.blackboard.set("goal", "1;0;0")
    planned = []
    for goal in ("1;0;0", "1;0;0", "2;0;0", "2;0;0"):
        tree.blackboard.set("goal", goal)
        _, log = tick(tree)
        planned.append(("tick", "plan") in log)
    assert planned == [True, False, True, False]


def test_global_updated_goal_is_not_reset_with_its_parent() -> None:
    tree = load_tree_string(
        '<root BTCPP_format="4"><BehaviorTree ID="M"><GlobalUpdatedGoal/></BehaviorTree></root>',
        blackboard={"goal": "1;2;0"},
    )
    seen = []
    for goal in ("1;2;0", "1;2;0", "4;2;0", "4;2;0"):
        tree.blackboard.set("goal", goal)
        seen.append(tree.tick().value)  # the root is reset after each tick
    assert seen == ["FAILURE", "FAILURE", "SUCCESS", "FAILURE"]


def test_selectors_select_the_default() -> None:
    tree = load_tree_string(
        '<root BTCPP_format="4"><BehaviorTree ID="M"><Sequence>'
        '<PlannerSelector selected_planner="{p}" default_planner="GridBased"/>'
        '<ControllerSelector selected_controller="{c}" default_controller="FollowPath"/>'
        '<GoalCheckerSelector selected_goal_checker="{g}" default_goal_checker="general"/>'
        "</Sequence></BehaviorTree></root>"
    )
    assert tree.tick().value == "SUCCESS"
    assert [tree.blackboard.get(k) for k in "pcg"] == ["GridBased", "FollowPath", "general"]


def straight(length: float, n: int = 11) -> Nav2Path:
    xs = np.linspace(0.0, length, n)
    return Nav2Path(np.column_stack([xs, np.zeros(n), np.zeros(n)]), length=length)


def test_truncate_path_stops_short_of_the_goal_facing_it() -> None:
    tree = load_tree_string(
        '<root BTCPP_format="4"><BehaviorTree ID="M"><TruncatePath input_path="{path}" '
        'output_path="{short}" distance="0.45"/></BehaviorTree></root>',
        blackboard={"path": straight(2.0)},
    )
    assert tree.tick().value == "SUCCESS"
    short = tree.blackboard.get("short")
    assert short.goal == pytest.approx((1.4, 0.0, 0.0))  # 0.6 m before the end: >= 0.45
    assert short.length == pytest.approx(1.4)


def test_path_longer_on_approach_ticks_its_child_for_a_much_longer_path_near_the_goal() -> None:
    tree, _ = make(
        f"<PipelineSequence><PathLongerOnApproach path=\"{{path}}\" prox_len=\"3\" "
        f"length_factor=\"2\">{kid('wait')}</PathLongerOnApproach>{kid('drive')}"
        "</PipelineSequence>",
        {"wait": "RS", "drive": "R"},
    )
    ran = []
    for path in (straight(2.5), straight(2.0), straight(5.0), straight(5.0)):
        tree.blackboard.set("path", path)
        _, log = tick(tree)
        ran.append(("tick", "wait") in log)
    # first tick: only records; shorter path: no; 5 m after 2 m within 3 m of the goal: the
    # child runs (RUNNING), then finishes (SUCCESS)
    assert ran == [False, False, True, True]
    tree.blackboard.set("path", straight(4.5))  # not near the goal any more (5 m before)
    _, log = tick(tree)
    assert ("tick", "wait") not in log


def test_initial_pose_received_reads_the_blackboard() -> None:
    body = '<root BTCPP_format="4"><BehaviorTree ID="M"><InitialPoseReceived/></BehaviorTree>' \
           "</root>"
    assert load_tree_string(body, blackboard={"initial_pose_received": True}).tick().value == \
        "SUCCESS"
    assert load_tree_string(body).tick().value == "FAILURE"
