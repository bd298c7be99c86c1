"""Scenario B authored in Python: the same tree as trees/sawyer_blocks_to_bin.xml.

Run it against the world (or a variant, e.g. worlds/sawyer_table_bin_moved.yaml):
    python examples/sawyer_blocks_to_bin.py --seed 3 [--world worlds/sawyer_table_bin_moved.yaml]
or print it as BehaviorTree.CPP XML (for Groot2):
    python examples/sawyer_blocks_to_bin.py --xml
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bt_manip.behaviours.arm import Lift, MoveJoints, MoveToPose
from bt_manip.behaviours.conditions import IsHolding, ObjectInRegion
from bt_manip.behaviours.gripper import CloseGripper, OpenGripper
from bt_manip.behaviours.regions import DropPoint
from bt_manip.behaviours.world_ops import DeleteModel, SpawnModel
from bt_manip.bt import SubTree, Tree, TreeContext, to_xml
from bt_manip.bt.controls import Fallback, Sequence
from bt_manip.bt.decorators import ForceSuccess, RetryUntilSuccessful
from bt_manip.bt.leaves import Script, ScriptCondition
from bt_manip.run.context import RunContext

ROOT = Path(__file__).resolve().parents[1]

CELLS = [0, 1, 2, 3, 4, 5, 6, 7, 8, 4]
"""The cell of the 3 x 3 grid over the bin where each block is let go (the centre again for
the tenth)."""


def block_to_bin() -> Sequence:
    """One block: its drop point over the bin, then pick top-down, lift, carry over the drop
    point, release, check; retried once, otherwise skipped (gripper opened, hand raised,
    counted)."""
    pick_and_place = Sequence("pick_and_place", children=[
        OpenGripper("open", opening=0.06),
        MoveToPose("reach_block", object="{block}", match_object_yaw=True, approach=0.12,
                   path="line"),
        CloseGripper("grasp", require_object=True),
        Lift("lift", height=0.15),
        IsHolding("still_holding", object="{block}"),
        MoveToPose("over_bin", position="{drop}", orientation="{drop_tool}", path="line"),
        OpenGripper("release"),
        Lift("retreat", height=0.08),
        ObjectInRegion("landed_in_bin", object="{block}", inside="bin"),
        Script("count", code="in_bin += 1"),
    ])
    skip = Sequence("skip_block", children=[
        OpenGripper("let_go"),
        ForceSuccess(child=Lift("clear_table", height=0.1)),
        Script("count_skip", code="skipped += 1"),
    ])
    return Sequence("block_to_bin", children=[
        DropPoint("drop_point", region="bin", index="{cell}", rows=3, cols=3, margin=0.02,
                  clearance=0.0625, robot="sawyer", point="{drop}",
                  tool_orientation="{drop_tool}"),
        Fallback("block_or_skip", children=[
            RetryUntilSuccessful("try_twice", num_attempts=2, child=pick_and_place),
            skip,
        ]),
    ])


def count_if_in_bin() -> ForceSuccess:
    """At the end: one more in ``resting_in_bin`` if the block rests in the bin."""
    return ForceSuccess(child=Sequence(children=[
        ObjectInRegion(object="{block}", inside="bin"),
        Script(code="resting_in_bin += 1"),
    ]))


def build(context: TreeContext | None = None) -> Tree:
    """The whole task: spawn the blocks, start at home, each of the ten blocks, back home,
    count the blocks resting in the bin, delete the blocks, check."""
    names = [f"block_{i}" for i in range(len(CELLS))]
    blocks = [
        SubTree("BlockToBin", child=block_to_bin(), block=f"block_{i}", cell=str(cell),
                in_bin="{in_bin}", skipped="{skipped}")
        for i, cell in enumerate(CELLS)
    ]
    root = Sequence("blocks_to_bin", children=[
        Script("init", code="in_bin := 0; skipped := 0; resting_in_bin := 0"),
        Sequence("spawn_blocks", children=[SpawnModel(model=n) for n in names]),
        MoveJoints("start_at_home", state="home"),
        *blocks,
        MoveJoints("back_home", state="home"),
        Sequence("count_resting_in_bin", children=[
            SubTree("CountIfInBin", child=count_if_in_bin(), block=n,
                    resting_in_bin="{resting_in_bin}")
            for n in names
        ]),
        Sequence("delete_blocks", children=[DeleteModel(model=n) for n in names]),
        ScriptCondition("at_least_one_in_bin", code="resting_in_bin >= 1"),
    ])
    return Tree(root, context=context or TreeContext(), tree_id="BlocksToBin")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--world", default=str(ROOT / "worlds" / "sawyer_table.yaml"))
    parser.add_argument("--xml", action="store_true", help="print the tree as XML and stop")
    args = parser.parse_args()
    if args.xml:
        print(to_xml(build()))
        return 0
    from bt_manip.run.runner import Runner
    from bt_manip.sim.world import World

    with World(args.world, seed=args.seed) as world:
        tree = build(RunContext.for_world(world))
        report = Runner(tree, world).run()
        print(report.summary())
        print("blocks resting in the bin:", tree.blackboard.as_dict()["resting_in_bin"])
        return report.exit_code


if __name__ == "__main__":
    raise SystemExit(main())
