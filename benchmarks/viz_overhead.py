"""What the live view and the replay recorder cost, and how big a Scenario A replay gets.

Run: ``.venv/bin/python benchmarks/viz_overhead.py [--sim 30] [--no-browser] [--record-sim 240]``

The workload drives the Husky + UR3 of ``worlds/tb3_house.yaml`` in slow circles while the arm
sweeps all six joints (every link moves, the worst case for the viewer), ticked at 20 Hz.

Lines printed (JSON):

- ``paced``: wall time of ``--sim`` seconds of sim at real-time pacing (1x), headless and with
  the live view (meshcat server + tree page, and a headless Chromium watching the page unless
  ``--no-browser``); ``overhead_pct`` is the extra wall time of the viewed run.
- ``flat_out``: the same without pacing: what each tick costs with and without the viewer
  (the viewer's own cost per tick, which pacing hides).
- ``record``: ``--record-sim`` seconds (a few minutes, like Scenario A) recorded at 20 Hz:
  page size in MB and the time to write it.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import py_trees
from py_trees.common import Status

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from bt_manip.cli.args import positive  # noqa: E402
from bt_manip.run.runner import Runner, RunOptions  # noqa: E402
from bt_manip.sim.world import World  # noqa: E402

WORLD = REPO / "worlds" / "tb3_house.yaml"


class Wander(py_trees.behaviour.Behaviour):
    """Drives in circles and sweeps the arm for ``duration`` s of sim, then SUCCESS."""

    def __init__(self, world: Any, duration: float) -> None:
        super().__init__("wander")
        self.world, self.duration = world, duration

    def update(self) -> Status:
        robot = next(iter(self.world.robots.values()))
        t = self.world.time
        if t >= self.duration:
            robot.stop_base()
            return Status.SUCCESS
        robot.set_base_twist(0.3, 0.25)
        home = [1.5708, -1.5708, 0.0, -1.5708, 0.0, 0.0]
        robot.set_arm_targets([q + 0.4 * math.sin(0.5 * t + k) for k, q in enumerate(home)])
        return Status.RUNNING


class WanderTree:
    def __init__(self, world: Any, duration: float) -> None:
        self.root = py_trees.composites.Sequence("main", memory=True,
                                                 children=[Wander(world, duration)])

    def tick(self) -> Status:
        self.root.tick_once()
        return self.root.status

    def halt(self) -> None:
        self.root.stop(Status.INVALID)


def _run(sim: float, realtime: float | None, viewed: bool, browser: bool) -> dict[str, Any]:
    from bt_manip.viz.live import LiveOptions, LiveViewer

    world = World(WORLD, seed=0)
    tree = WanderTree(world, sim)
    hooks: list[Any] = []
    live = None
    watcher = None
    if viewed:
        live = LiveViewer(world, tree, LiveOptions(port=0), say=lambda s: None)
        if not live.start():
            raise SystemExit("the live view did not start")
        hooks.append(live)
        if browser:
            watcher = _Browser(live.page.url if live.page else live.link.web_url)
    t0 = time.perf_counter()
    report = Runner(tree, world, RunOptions(realtime=realtime), on_tick=hooks).run()
    wall = time.perf_counter() - t0
    if watcher is not None:
        watcher.close()
    if live is not None:
        live.close()
    world.close()
    return {"wall_s": round(wall, 3), "ticks": report.ticks, "sim_s": round(report.sim_time, 3),
            "status": report.status}


class _Browser:
    """A headless Chromium showing the live page for the whole run."""

    def __init__(self, url: str) -> None:
        from playwright.sync_api import sync_playwright

        self._pw = sync_playwright().start()
        self._browser = self._pw.chromium.launch(
            executable_path=shutil.which("chromium"),
            args=["--headless", "--no-sandbox", "--disable-gpu", "--use-gl=swiftshader",
                  "--enable-unsafe-swiftshader", "--no-first-run", "--disable-sync",
                  "--disable-background-networking", "--disable-component-update"],
        )
        self.page = self._browser.new_page(viewport={"width": 1200, "height": 700})
        self.page.goto(url)
        self.page.wait_for_timeout(1500)

    def close(self) -> None:
        self._browser.close()
        self._pw.stop()


def _record(sim: float) -> dict[str, Any]:
    from bt_manip.viz.recorder import Recorder

    world = World(WORLD, seed=0)
    tree = WanderTree(world, sim)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "scenario_a.html"
        recorder = Recorder(out, world, tree)
        t0 = time.perf_counter()
        report = Runner(tree, world, RunOptions(), on_tick=[recorder]).run()
        run_wall = time.perf_counter() - t0
        t0 = time.perf_counter()
        recorder.close()
        write = time.perf_counter() - t0
        size = out.stat().st_size
    world.close()
    return {"sim_s": round(report.sim_time, 2), "frames": len(recorder.rec.times),
            "size_mb": round(size / 1e6, 2), "run_wall_s": round(run_wall, 2),
            "write_s": round(write, 2)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sim", type=positive(float), default=30.0,
                        help="sim seconds per paced run")
    parser.add_argument("--no-browser", action="store_true")
    parser.add_argument("--record-sim", type=positive(float), default=240.0)
    args = parser.parse_args()
    browser = not args.no_browser and shutil.which("chromium") is not None

    headless = _run(args.sim, 1.0, False, False)
    viewed = _run(args.sim, 1.0, True, browser)
    extra = 100.0 * (viewed["wall_s"] - headless["wall_s"]) / headless["wall_s"]
    print(json.dumps({"case": "paced", "realtime": 1.0, "browser": browser,
                      "headless": headless, "viz": viewed, "overhead_pct": round(extra, 2)}))

    headless = _run(args.sim, None, False, False)
    viewed = _run(args.sim, None, True, browser)
    per_tick = 1000.0 * (viewed["wall_s"] - headless["wall_s"]) / max(1, viewed["ticks"])
    print(json.dumps({"case": "flat_out", "browser": browser, "headless": headless,
                      "viz": viewed, "viewer_ms_per_tick": round(per_tick, 3),
                      "tick_period_ms": 50.0}))

    print(json.dumps({"case": "record", **_record(args.record_sim)}))


if __name__ == "__main__":
    main()
