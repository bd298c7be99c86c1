"""``bt-manip run --groot / --btlog``, ``bench --btlog-failures``, the Groot2 publisher next to
the meshcat viewer, and paced runs after a pause."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
import threading
import urllib.request
from pathlib import Path
from typing import Any

import pytest
from groot_client import GrootClient, sync_subscription
from test_groot_breakpoints import status_of, uid_of, wait_for_breakpoint

from bt_manip.bt import TreeContext, load_tree
from bt_manip.cli import main
from bt_manip.groot import GrootPublisher, TreeMonitor, read_btlog
from bt_manip.run import runner as runner_module
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.world import World
from bt_manip.viz.live import LiveOptions, LiveViewer

ROOT = Path(__file__).resolve().parents[2]
ROOM = ROOT / "tests" / "viz" / "viz_room.yaml"
DEMO = ROOT / "trees" / "builtins_demo.xml"


def _tree(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "t.xml"
    path.write_text('<root BTCPP_format="4" main_tree_to_execute="Main">'
                    f'<BehaviorTree ID="Main">{body}</BehaviorTree></root>')
    return path


def test_cli_serves_groot2_with_robot_models_pauses_on_a_breakpoint_and_writes_btlog(
        tmp_path: Path) -> None:
    tree = _tree(tmp_path, '<Sequence><Sleep msec="1500"/><AlwaysFailure name="done"/>'
                           "</Sequence>")
    btlog = tmp_path / "run.btlog"
    proc = subprocess.Popen(
        [sys.executable, "-m", "bt_manip.cli", "run", str(tree), "--groot", "0",
         "--btlog", str(btlog), "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)
    client = None
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert line.startswith("groot2: serving the tree on 127.0.0.1:"), line
        port = int(line.split("127.0.0.1:")[1].split()[0])
        client = GrootClient(port)
        fulltree = client.request("T")[1].decode()
        assert '<BehaviorTree ID="Main" _fullpath="">' in fulltree
        assert '<Action ID="Navigate">' in fulltree  # robot nodes are in the model
        done = uid_of(fulltree, "done")
        assert done == 3
        hook = {"enabled": True, "uid": done, "mode": 0, "once": True,
                "desired_status": "IDLE", "position": 0}
        client.request("I", json.dumps(hook))
        running = threading.Thread(target=proc.wait)
        running.start()
        assert wait_for_breakpoint(client, running)[1] == b"3"
        assert status_of(client.request("S")[1], 1) == 1  # the Sequence is RUNNING
        client.request("U", json.dumps({"uid": done, "desired_status": "SUCCESS",
                                        "position": 0, "remove_when_done": True}))
        out, err = proc.communicate(timeout=120)
    finally:
        if client is not None:
            client.close()
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err  # the forced SUCCESS replaced AlwaysFailure
    assert "paused at the breakpoint on AlwaysFailure 'done'" in out
    log = read_btlog(btlog)
    assert log.xml == fulltree
    changes = [(uid, status) for _, uid, status in log.transitions]
    assert changes[:2] == [(1, 1), (2, 1)]
    assert (3, 2) in changes and (3, 3) not in changes


def test_groot_port_in_use_and_bad_port_exit_2(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = _tree(tmp_path, "<AlwaysSuccess/>")
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["run", str(tree), "--quiet", "--groot", str(port)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"--groot: cannot listen on 127.0.0.1:{port}: ")
    with pytest.raises(SystemExit) as exc:
        main(["run", str(tree), "--groot", "70000"])
    assert exc.value.code == 2
    assert "argument --groot: must be a port from 1 to 65534" in capsys.readouterr().err


def test_bench_keeps_a_btlog_per_failed_episode_only(tmp_path: Path) -> None:
    failing = _tree(tmp_path, '<Sequence><AlwaysSuccess/><AlwaysFailure name="boom"/>'
                              "</Sequence>")
    logs = tmp_path / "logs"
    code = main(["bench", str(failing), "--world", str(ROOM), "--runs", "2", "--jobs", "1",
                 "--out", str(tmp_path / "out"), "--btlog-failures", str(logs)])
    assert code == 1
    assert sorted(p.name for p in logs.iterdir()) == ["seed-0.btlog", "seed-1.btlog"]
    log = read_btlog(logs / "seed-1.btlog")
    assert [(uid, status) for _, uid, status in log.transitions][:4] == [
        (1, 1), (2, 2), (3, 3), (2, 0)]
    passing = tmp_path / "ok.xml"
    passing.write_text(failing.read_text().replace("AlwaysFailure", "AlwaysSuccess"))
    code = main(["bench", str(passing), "--world", str(ROOM), "--runs", "1", "--jobs", "1",
                 "--seed", "5", "--out", str(tmp_path / "out2"), "--btlog-failures", str(logs)])
    assert code == 0
    assert not (logs / "seed-5.btlog").exists()


def test_groot_publisher_and_meshcat_viewer_serve_the_same_run() -> None:
    world = World(ROOM, seed=3)
    tree = load_tree(str(DEMO), context=TreeContext(clock=world.clock, world=world))
    # kept serving after the run (as --keep-serving does): the page is read after it
    live = LiveViewer(world, tree, LiveOptions(port=0, max_fps=1e6, keep_serving=True),
                      say=lambda s: None)
    monitor = TreeMonitor(tree, world.clock.now)
    publisher = GrootPublisher(monitor, port=0)
    client = GrootClient(publisher.port)
    sync_subscription(client, publisher)
    outcome: dict[str, Any] = {}
    try:
        assert live.start() and live.page is not None
        plan_a = uid_of(client.request("T")[1].decode(), "plan_a")
        client.request("I", json.dumps({"enabled": True, "uid": plan_a, "mode": 0,
                                        "once": True, "desired_status": "IDLE",
                                        "position": 0}))
        run = threading.Thread(target=lambda: outcome.update(
            report=Runner(tree, world, RunOptions(), on_tick=[live]).run()))
        run.start()
        assert wait_for_breakpoint(client, run)[1] == str(plan_a).encode()
        with urllib.request.urlopen(live.page.url + "state.json", timeout=5) as res:
            state = json.loads(res.read())
        assert state["result"] in ("", None, "RUNNING")  # the page answers while paused
        client.request("U", json.dumps({"uid": plan_a, "desired_status": "IDLE",
                                        "position": 0, "remove_when_done": True}))
        run.join(120)
        with urllib.request.urlopen(live.page.url + "state.json", timeout=5) as res:
            state = json.loads(res.read())
        assert state["result"] == "SUCCESS" == outcome["report"].status
        assert status_of(client.request("S")[1], plan_a) == 13  # failed, then reset
    finally:
        client.close()
        publisher.close()
        live.stop()
        world.close()


class _FakeWorld:
    rate_hz = 240.0

    def __init__(self) -> None:
        self.time = 0.0

    def step(self, n: int) -> None:
        self.time += n / self.rate_hz


def test_paced_run_goes_on_at_its_pace_after_a_pause(monkeypatch: pytest.MonkeyPatch) -> None:
    """A run paused for 10 s (wall) resumes at real time instead of rushing 10 s of sim."""
    wall = {"t": 0.0}
    sleeps: list[float] = []

    class Tree:
        root = None
        ticks = 0

        def tick(self) -> Any:
            self.ticks += 1
            if self.ticks == 5:
                wall["t"] += 10.0  # a breakpoint held the tick for 10 s
            from bt_manip.bt.status import NodeStatus
            return NodeStatus.SUCCESS if self.ticks == 40 else NodeStatus.RUNNING

        def halt(self) -> None: ...

        def node_records(self) -> list[Any]:
            return []

    def sleep(seconds: float) -> None:
        sleeps.append(seconds)
        wall["t"] += seconds

    monkeypatch.setattr(runner_module.time, "perf_counter", lambda: wall["t"])
    monkeypatch.setattr(runner_module.time, "sleep", sleep)
    report = Runner(Tree(), _FakeWorld(), RunOptions(realtime=1.0)).run()
    assert report.status == "SUCCESS"
    assert len(sleeps) == 39 - 1  # every tick but the one after the pause waits its turn
    assert report.wall_time == pytest.approx(10.0 + report.sim_time, abs=0.1)
