"""Scenario B authored in Python: the same tree as trees/sawyer_blocks_to_bin.xml.

Run it against the world:
    python examples/sawyer_blocks_to_bin.py --seed 3
or print it as BehaviorTree.CPP XML (for Groot2):
    python examples/sawyer_blocks_to_bin.py --xml
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bt_manip.behaviours.arm import Lift, MoveJoints, MoveToPose
from bt_manip.behaviours.conditions import IsHolding, ObjectInRegion
from bt_manip.behaviours.gripper import CloseGripper, OpenGripper
from bt_manip.behaviours.world_ops import DeleteModel, SpawnModel
from bt_manip.bt import SubTree, Tree, TreeContext, to_xml
from bt_manip.bt.controls import Fallback, Sequence
from bt_manip.bt.decorators import ForceSuccess, RetryUntilSuccessful
from bt_manip.bt.leaves import Script, ScriptCondition
from bt_manip.run_context import RunContext

ROOT = Path(__file__).resolve().parents[1]

BIN_GRID = [(x, y) for y in (-0.33, -0.25, -0.17) for x in (0.67, 0.75, 0.83)] + [(0.75, -0.25)]
"""Where each block is let go: a 3 x 3 grid over the bin, then the centre again."""
DROP_HEIGHT = 0.93


def block_to_bin() -> Fallback:
    """One block: pick top-down, lift, carry over its spot, release, check; retried once,
    otherwise skipped (gripper opened, hand raised, counted)."""
    pick_and_place = Sequence("pick_and_place", children=[
        OpenGripper("open", opening=0.075),
        MoveToPose("reach_block", object="{block}", match_object_yaw=True, approach=0.12,
                   path="line"),
        CloseGripper("grasp", require_object=True),
        Lift("lift", height=0.15),
        IsHolding("still_holding", object="{block}"),
        MoveToPose("over_bin", position="{drop}", path="line"),
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
    return Fallback("block_or_skip", children=[
        RetryUntilSuccessful("try_twice", num_attempts=2, child=pick_and_place),
        skip,
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
    names = [f"block_{i}" for i in range(len(BIN_GRID))]
    blocks = [
        SubTree("BlockToBin", child=block_to_bin(), block=f"block_{i}",
                drop=f"{x:g};{y:g};{DROP_HEIGHT:g}", in_bin="{in_bin}", skipped="{skipped}")
        for i, (x, y) in enumerate(BIN_GRID)
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
    parser.add_argument("--xml", action="store_true", help="print the tree as XML and stop")
    args = parser.parse_args()
    if args.xml:
        print(to_xml(build()))
        return 0
    from bt_manip.runner import Runner
    from bt_manip.sim.world import World

    with World(ROOT / "worlds" / "sawyer_table.yaml", seed=args.seed) as world:
        tree = build(RunContext.for_world(world))
        report = Runner(tree, world).run()
        print(report.summary())
        print("blocks resting in the bin:", tree.blackboard.as_dict()["resting_in_bin"])
        return report.exit_code


if __name__ == "__main__":
    raise SystemExit(main())
