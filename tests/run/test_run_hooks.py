"""The runner owns its hooks: it calls them after each tick and closes each of them once when
the run ends, however it ends (RunHook protocol, bt_manip.run.hooks)."""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest

from bt_manip.bt import TreeContext, load_tree_string
from bt_manip.bt.status import NodeStatus
from bt_manip.clock import ManualClock
from bt_manip.run.hooks import RunHook, close_hooks
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.run.status import RunStatus


class Watcher:
    """A run hook that notes its ticks and its closes."""

    def __init__(self, log: list[str], name: str) -> None:
        self.log = log
        self.name = name
        self.ticks = 0
        self.closed = 0

    def __call__(self, runner: Runner) -> None:
        self.ticks += 1
        self.log.append(f"{self.name} tick {runner.ticks}")

    def close(self) -> None:
        self.closed += 1
        self.log.append(f"{self.name} closed")


class _Tree:
    """Two RUNNING ticks, then what ``last`` says (a callable may raise)."""

    root = None

    def __init__(self, last: Any) -> None:
        self.last = last
        self.n = 0
        self.halted = 0

    def tick(self) -> NodeStatus:
        self.n += 1
        if self.n < 3:
            return NodeStatus.RUNNING
        return self.last() if callable(self.last) else self.last

    def halt(self) -> None:
        self.halted += 1


def _interrupt() -> NodeStatus:
    raise KeyboardInterrupt


def _bug() -> NodeStatus:
    raise RuntimeError("a bug in a node")


@pytest.mark.parametrize("last,status", [
    (NodeStatus.SUCCESS, RunStatus.SUCCESS),
    (NodeStatus.FAILURE, RunStatus.FAILURE),
    (_interrupt, RunStatus.INTERRUPTED),
])
def test_hooks_are_called_after_each_tick_and_closed_once_in_order(last: Any,
                                                                   status: RunStatus) -> None:
    log: list[str] = []
    first, second = Watcher(log, "a"), Watcher(log, "b")
    seen: list[int] = []
    runner = Runner(_Tree(last), options=RunOptions(tick_hz=1000.0),
                    on_tick=[first, lambda r: seen.append(r.ticks), second])
    report = runner.run()
    assert report.status is status
    ticks = 3 if status is not RunStatus.INTERRUPTED else 2
    assert first.ticks == second.ticks == ticks and seen == list(range(1, ticks + 1))
    assert log[-2:] == ["a closed", "b closed"] and first.closed == second.closed == 1
    runner.close_hooks()  # closing again is the hooks' business: each close is idempotent
    assert first.closed == second.closed == 2


def test_hooks_are_closed_when_the_run_raises() -> None:
    log: list[str] = []
    hook = Watcher(log, "a")
    with pytest.raises(RuntimeError, match="a bug in a node"):
        Runner(_Tree(_bug), options=RunOptions(tick_hz=1000.0), on_tick=[hook]).run()
    assert hook.closed == 1 and log[-1] == "a closed"


def test_every_hook_is_closed_even_when_one_close_raises() -> None:
    log: list[str] = []

    class Broken(Watcher):
        def close(self) -> None:
            super().close()
            raise OSError("disk full")

    broken, after = Broken(log, "a"), Watcher(log, "b")
    with pytest.raises(OSError, match="disk full"):
        close_hooks([broken, after])
    assert broken.closed == after.closed == 1


def test_what_is_a_run_hook() -> None:
    assert isinstance(Watcher([], "a"), RunHook)
    assert not isinstance(lambda runner: None, RunHook)  # a plain callable has nothing to close


def test_a_real_tree_run_closes_its_console_log() -> None:
    from io import StringIO

    from bt_manip.viz.console import StatusLog

    tree = load_tree_string('<root BTCPP_format="4"><BehaviorTree ID="M"><Sequence>'
                            '<AlwaysSuccess name="ok"/></Sequence></BehaviorTree></root>',
                            context=TreeContext(clock=ManualClock()))

    class Stream(StringIO):
        flushed = 0

        def flush(self) -> None:
            self.flushed += 1
            super().flush()

    stream = Stream()
    log = StatusLog(tree, stream)
    report = Runner(tree, options=RunOptions(tick_hz=1000.0), on_tick=[log]).run()
    assert report.status is RunStatus.SUCCESS
    assert stream.flushed == 1 and "ok: IDLE -> SUCCESS" in stream.getvalue()


def test_run_options_are_frozen() -> None:
    options = RunOptions()
    with pytest.raises(dataclasses.FrozenInstanceError):
        options.realtime = 1.0  # type: ignore[misc]
    paced = dataclasses.replace(options, realtime=1.0)
    assert paced.realtime == 1.0 and options.realtime is None
