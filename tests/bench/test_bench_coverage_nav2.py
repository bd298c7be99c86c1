"""Coverage of Nav2's default tree: a crate that falls in front of the robot takes it through
the recovery branch, and the coverage shows the RoundRobin of recoveries exercised."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_manip.bench.coverage import bench_coverage, tree_outline
from bt_manip.bench.episodes import run_one
from bt_manip.episode import EpisodeSpec
from bt_manip.run.faults import parse_fault
from bt_manip.run.runner import RunOptions

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_TREE = ROOT.parent / "shared" / "samples" / "nav2" / \
    "navigate_to_pose_w_replanning_and_recovery.xml"
ROUND_ROBIN = "NavigateRecovery/Sequence/RecoveryFallback/RecoveryActions"

pytestmark = pytest.mark.skipif(
    not DEFAULT_TREE.is_file(), reason="Nav2's sample trees are not in ../shared/samples/nav2")


def test_a_crate_in_front_of_the_robot_exercises_the_recovery_round_robin() -> None:
    spec = EpisodeSpec(tree=str(DEFAULT_TREE), world=str(ROOT / "worlds" / "tb3_house.yaml"),
                       seed=0, blackboard={"goal": "2.616;-0.715;0.848"},
                       inject=[parse_fault("block:1")],
                       options=RunOptions(max_sim_time=120.0))
    result = run_one(spec)
    assert result.status == "SUCCESS"
    coverage = bench_coverage(tree_outline(spec), [result]).to_json()
    branches = {br["path"]: br for bn in coverage["branch_nodes"] for br in bn["branches"]}
    # the RecoveryNode's recovery ran, and in it the RoundRobin's first recovery (clearing)
    assert branches["NavigateRecovery/Sequence"]["episodes"] == 1
    assert branches[ROUND_ROBIN]["episodes"] == 1 and branches[ROUND_ROBIN]["recovery"]
    assert branches[ROUND_ROBIN + "/ClearingActions"]["won"] == 1
    never = {r["path"] for r in coverage["recoveries"]["never_exercised"]}
    assert ROUND_ROBIN not in never
    assert {ROUND_ROBIN + "/Spin", ROUND_ROBIN + "/Wait", ROUND_ROBIN + "/BackUp"} <= never
