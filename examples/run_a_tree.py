"""Run a tree file from Python with ``bt_manip.run_tree``, and look at the world as it runs.

    python examples/run_a_tree.py [--seed N] [--world worlds/sawyer_table.yaml]

runs ``trees/sawyer_stack_two.xml`` (the Sawyer stacks block_1 on block_0) as ``bt-manip run``
would, and prints the result and where the two blocks ended up. The shipped files are named by
their relative paths, from any folder. A hook (any callable taking the runner; one with a
``close()`` is closed at the end) is called after every tick: here it keeps the blocks'
positions.
"""

from __future__ import annotations

import argparse
from typing import Any

import bt_manip

TREE = "trees/sawyer_stack_two.xml"
WORLD = "worlds/sawyer_table.yaml"
BLOCKS = ("block_0", "block_1")


class BlockPositions:
    """A run hook: the position (x, y, z of the centre, m) of each block after the last tick
    at which it was in the world."""

    def __init__(self, names: tuple[str, ...]) -> None:
        self.names = names
        self.positions: dict[str, tuple[float, float, float]] = {}

    def __call__(self, runner: Any) -> None:
        world = runner.world
        for name in self.names:
            if name in world.movable:
                self.positions[name] = world.body_pose(name).xyz

    def close(self) -> None:
        """Nothing to write: the positions stay readable after the run."""


def stack(seed: int = 0, world: str = WORLD) -> tuple[Any, dict[str, tuple[float, float, float]]]:
    """Run the stacking tree; its run report and the blocks' final positions."""
    watch = BlockPositions(BLOCKS)
    report = bt_manip.run_tree(TREE, world=world, seed=seed, hooks=[watch], max_sim_time=120)
    return report, watch.positions


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--world", default=WORLD)
    args = parser.parse_args()
    report, positions = stack(args.seed, args.world)
    print(f"{report.status.value}: {report.reason or 'done'} "
          f"({report.sim_time:.1f} s of sim time)")
    for name, (x, y, z) in positions.items():
        print(f"  {name} at x={x:.3f} y={y:.3f} z={z:.3f}")
    return report.exit_code


if __name__ == "__main__":
    raise SystemExit(main())
