"""Scenario A authored in Python: the same tree as trees/husky_carry_wall.xml.

Run it against the world:
    python examples/husky_carry_wall.py --seed 3
or print it as BehaviorTree.CPP XML (for Groot2):
    python examples/husky_carry_wall.py --xml
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bt_manip.behaviours.arm import Lift, MoveJoints, MoveJointsSequentially
from bt_manip.behaviours.attach import Attach
from bt_manip.behaviours.conditions import CarriedClear, IsAttached, ObjectAbove
from bt_manip.behaviours.get_clear import GetClear
from bt_manip.behaviours.gripper import CloseGripper, OpenGripper
from bt_manip.behaviours.navigate import Navigate
from bt_manip.bt import SubTree, Tree, TreeContext, to_xml
from bt_manip.bt.controls import Fallback, Sequence
from bt_manip.bt.decorators import ForceSuccess, RetryUntilSuccessful
from bt_manip.bt.leaves import AlwaysFailure
from bt_manip.run.context import RunContext

ROOT = Path(__file__).resolve().parents[1]

PREGRASP_DEG = [70.0, 11.0, 78.0, -56.0, 85.0, 4.0]
"""The scenario's pre-grasp joints (deg), moved one at a time in PREGRASP_ORDER."""
PREGRASP_ORDER = [0, 2, 3, 5, 4, 1]
LIFT_DEG = [0.0, -50.0, -30.0, 0.0, 0.0, 0.0]
TUCK_RAD = [1.5708, -3.05, 2.95, -0.1, -1.5708, 0.0]


def grasp_panel() -> Fallback:
    """One grasp attempt; on failure the arm backs off the way it came and the attempt fails."""
    approach_and_grasp = Sequence("approach_and_grasp", children=[
        RetryUntilSuccessful("reach_pregrasp", num_attempts=3, child=Fallback(
            "drive_or_back_off", children=[
                Navigate("to_pregrasp", goal="pregrasp_panel", xy_tolerance=0.03,
                         yaw_tolerance=0.03),
                Sequence("clear_and_drive_again", children=[
                    ForceSuccess(child=GetClear("get_clear", distance=0.5, near=0.3)),
                    AlwaysFailure("drive_failed"),
                ]),
            ])),
        MoveJointsSequentially("pregrasp_arm", targets=PREGRASP_DEG, order=PREGRASP_ORDER),
        CloseGripper("close_gripper", require_object=True),
        Attach("attach_panel", object="panel"),
    ])
    back_off = Sequence("back_off", children=[
        OpenGripper("release"),
        MoveJointsSequentially("arm_back", units="rad", targets=TUCK_RAD,
                               order=list(reversed(PREGRASP_ORDER))),
        AlwaysFailure("grasp_failed"),
    ])
    return Fallback("grasp_or_back_off", children=[approach_and_grasp, back_off])


def build(context: TreeContext | None = None) -> Tree:
    """Fetch the panel (grasp retried), lift it (straight up out of its stand first, then by
    joints), check the grasp, carry it to the goal."""
    root = Sequence("carry_wall_panel", children=[
        MoveJoints("tuck_arm", state="tuck"),
        OpenGripper("open_gripper"),
        RetryUntilSuccessful("grasp_attempts", num_attempts=4,
                             child=SubTree("GraspPanel", child=grasp_panel())),
        Lift("lift_out_of_stand", height=0.1, speed=0.3),
        Lift("lift_panel", deltas=LIFT_DEG, speed=0.3),
        Sequence("grasp_holds", children=[
            IsAttached("panel_attached", object="panel"),
            ObjectAbove("panel_off_floor", object="panel", height=0.1),
        ]),
        RetryUntilSuccessful("carry_attempts", num_attempts=3, child=Fallback(
            "carry_or_back_off", children=[
                Navigate("carry_to_goal", goal="goal"),
                Sequence("clear_and_retry", children=[
                    ForceSuccess(child=GetClear("back_up", distance=0.5, near=0.3)),
                    AlwaysFailure("carry_failed"),
                ]),
            ])),
        Sequence("delivered", children=[
            IsAttached("still_attached", object="panel"),
            ObjectAbove("still_off_floor", object="panel", height=0.1),
            CarriedClear("touched_nothing", object="panel"),
        ]),
    ])
    return Tree(root, context=context or TreeContext(), tree_id="CarryWallPanel")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--xml", action="store_true", help="print the tree as XML and stop")
    args = parser.parse_args()
    if args.xml:
        print(to_xml(build()))
        return 0
    from bt_manip.run.runner import Runner
    from bt_manip.sim.world import World

    with World(ROOT / "worlds" / "tb3_house.yaml", seed=args.seed) as world:
        report = Runner(build(RunContext.for_world(world)), world).run()
        print(report.summary())
        return report.exit_code


if __name__ == "__main__":
    raise SystemExit(main())
