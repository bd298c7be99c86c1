"""The advice of an IK failure names options that exist: the solver's in its own reason, the
node's ports in a tree; a straight line names the waypoint that failed and how far along it is."""

from __future__ import annotations

import re
from dataclasses import fields
from pathlib import Path

from bt_manip.behaviours.arm import _with_knobs
from bt_manip.kinematics.ik import IKOptions
from bt_manip.kinematics.reasons import SOLVER_KNOBS, not_converged

ROOT = Path(__file__).resolve().parents[2]

FAR = """<root BTCPP_format="4">
  <BehaviorTree ID="Far">
    <Sequence>
      <MoveToPose position="0.9;0.2;0.9" path="line"/>
      <MoveToPose position="0.5;0.0;0.78" orientation="0;0;0;1" path="line"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def test_the_solver_reason_names_ik_options_that_exist() -> None:
    reason = not_converged(0.02, 0.03, 200, 8000, 0.02, None)
    assert reason.endswith(SOLVER_KNOBS)
    named = set(re.findall(r"IKOptions\.(\w+)", reason))
    named |= {"time_budget", "position_only"}
    assert named <= {f.name for f in fields(IKOptions)}
    assert "partial target (IKOptions.free_axis" in reason


def test_a_node_names_its_own_ports_instead() -> None:
    reason = not_converged(0.02, 0.03, 200, 8000, 0.02, None)
    text = _with_knobs(reason, free_yaw=False, approach=0.1, path="line")
    assert "IKOptions" not in text
    assert text.endswith('try free_yaw="true" (the rotation about the tool axis left to the '
                         'solver), another orientation or offset, path="joint" (no straight '
                         "line from where the tool is), a shorter approach, the base moved "
                         "(Navigate, PlanBaseForGrasp)")
    # free_yaw already on: not offered again; other reasons are left alone
    assert "free_yaw" not in _with_knobs(reason, True, 0.0, "joint")
    assert _with_knobs("no kinematic chain a -> b", False, 0.0, "joint") == \
        "no kinematic chain a -> b"


def test_a_straight_line_names_its_failing_waypoint(tmp_path: Path) -> None:
    import bt_manip

    tree = tmp_path / "far.xml"
    tree.write_text(FAR, encoding="utf-8")
    report = bt_manip.run_tree(tree, world=ROOT / "worlds" / "sawyer_table.yaml",
                               max_sim_time=30)
    assert report.status.value == "FAILURE"
    match = re.search(r"on the straight line from \(0\.900, 0\.200, 0\.900\) to "
                      r"\(0\.500, 0\.000, 0\.780\), waypoint (\d+) of (\d+) \((\d+) % of the "
                      r"way\): no arm configuration reaches \(([-\d.]+), ([-\d.]+), ([-\d.]+)\)",
                      report.reason)
    assert match is not None, report.reason
    i, n, percent = (int(match[k]) for k in (1, 2, 3))
    assert 0 < i < n and percent == round(100 * i / n)
    x = float(match[4])
    assert abs(x - (0.9 - 0.4 * i / n)) < 1e-3  # the point named is that waypoint
    assert 'try free_yaw="true"' in report.reason and "IKOptions" not in report.reason


def test_other_arm_nodes_name_what_a_tree_can_change() -> None:
    """Lift, MoveToolBy, Place...: the solver's advice (Python options) becomes a tree's."""
    from bt_manip.behaviours.base import TREE_IK_KNOBS, ActionFailed, failure_reason
    from bt_manip.manipulation.cartesian import CartesianError

    reason = not_converged(0.02, 0.03, 200, 8000, 0.02, None)
    for exc in (ActionFailed(reason), CartesianError(f"lift: {reason}")):
        text = failure_reason(exc)
        assert "IKOptions" not in text and text.endswith(TREE_IK_KNOBS)
        assert text.startswith(str(exc)[: str(exc).index(SOLVER_KNOBS)])
    assert failure_reason(ActionFailed("gripper is empty")) == "gripper is empty"
