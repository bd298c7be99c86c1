"""Cost of watching a tree: Groot2 publisher and .btlog writer, next to BT.CPP's own.

The tree: a Sequence of 9 Sequences of 10 Sequences of 10 AlwaysSuccess (1,000 nodes; every
node changes status twice per tick: to SUCCESS, back to IDLE). bt-manip is ticked plain, with
its Groot2 publisher (REP/PUB bound, no client), and with a .btlog writer; BehaviorTree.CPP
4.8.2 (``behaviortreepy``) the same way with its Groot2Publisher and FileLogger2. Prints one
JSON line per case with the median time per tick.

    .venv/bin/python benchmarks/groot_overhead.py [--ticks N]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from bt_manip.bt import TreeContext, load_tree_string
from bt_manip.cli.args import positive
from bt_manip.clock import ManualClock
from bt_manip.groot import BtlogWriter, GrootPublisher, TreeMonitor


def tree_xml() -> str:
    leaves = "<AlwaysSuccess/>" * 10
    middle = f"<Sequence>{leaves}</Sequence>" * 10
    top = f"<Sequence>{middle}</Sequence>" * 9
    return (f'<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>{top}</Sequence>'
            "</BehaviorTree></root>")


def timed(tick: Callable[[], object], ticks: int) -> float:
    samples = []
    for _ in range(ticks):
        t0 = time.perf_counter()
        tick()
        samples.append(time.perf_counter() - t0)
    return statistics.median(samples) * 1e3


def ours(case: str, ticks: int, folder: Path) -> float:
    tree = load_tree_string(tree_xml(), context=TreeContext(clock=ManualClock()))
    closers: list[Callable[[], None]] = []
    if case != "plain":
        monitor = TreeMonitor(tree, tree.context.clock.now)
        if case == "groot2":
            closers.append(GrootPublisher(monitor, port=0).close)
        else:
            closers.append(BtlogWriter(folder / "ours.btlog", monitor).close)
    try:
        return timed(tree.tick, ticks)
    finally:
        for close in closers:
            close()


def theirs(case: str, ticks: int, folder: Path) -> float | None:
    try:
        import behaviortreepy as b
    except ImportError:
        return None
    factory = b.BehaviorTreeFactory()
    factory.register_behavior_tree_from_text(tree_xml())
    tree = factory.create_tree("Main", b.Blackboard.create())
    keep = None
    if case == "groot2":
        import socket

        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        keep = b.Groot2Publisher(tree, port)
    elif case == "btlog":
        keep = b.FileLogger(tree, str(folder / "btcpp.btlog"))
    result = timed(tree.tick_once, ticks)
    del keep
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--ticks", type=positive(int), default=300)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for case in ("plain", "groot2", "btlog"):
            print(json.dumps({
                "case": case, "nodes": 1000, "ticks": args.ticks,
                "bt_manip_ms_per_tick": round(ours(case, args.ticks, folder), 3),
                "btcpp_ms_per_tick": (None if (v := theirs(case, args.ticks, folder)) is None
                                      else round(v, 4)),
            }), flush=True)


if __name__ == "__main__":
    main()
