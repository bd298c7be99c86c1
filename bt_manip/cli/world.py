"""The ``world`` verb: load a world file, print its summary, optionally let it settle."""

from __future__ import annotations

import argparse
import math

from bt_manip.bundled import shipped_or_given
from bt_manip.cli.args import within
from bt_manip.sim.world import World


def add_world_arguments(world: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip world``."""
    world.add_argument("world", type=shipped_or_given, help="world file (YAML)")
    world.add_argument("--seed", type=int, default=0)
    world.add_argument(
        "--settle",
        type=within(float, 0.0, 3600.0),
        default=0.0,
        metavar="S",
        help="step S seconds of sim (0..3600) with no commands and report what moved",
    )
    world.set_defaults(func=cmd_world)


VERB_ARGUMENTS = {"world": add_world_arguments}
"""The verbs of this module and the function that adds each one's arguments."""


def cmd_world(args: argparse.Namespace) -> int:
    """Print the world's summary; with ``--settle``, the largest drift after S seconds."""
    with World(args.world, seed=args.seed) as world:
        print(world.summary())
        if args.settle > 0:
            before = world.snapshot()
            world.step(round(args.settle * world.rate_hz))
            after = world.snapshot()
            worst = (
                max(
                    (math.dist(before[k]["pos"], after[k]["pos"]), k) for k in before if k != "time"
                )
                if len(before) > 1
                else (0.0, "-")
            )
            print(
                f"  after {args.settle:g} s of sim with no commands, the largest drift is "
                f"{worst[0] * 1000:.3f} mm ({worst[1]})"
            )
    return 0
