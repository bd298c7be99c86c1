"""What watches a run: the :class:`RunHook` protocol.

A run hook is called after every tick with the runner (``hook(runner)``: read
``runner.sim_time``, ``runner.ticks``, ``runner.tree``, ``runner.world``) and closed once the
run has ended (``hook.close()``). The :class:`~bt_manip.run.runner.Runner` owns the hooks it is
given: it calls them in order after each tick and closes every one of them, in the same order,
in a ``finally`` when its run ends, however it ends. ``close()`` must be idempotent: whoever
built a hook may close it again.

``close()`` finishes what the hook does for the run: a recorder writes its replay page, a
console view shows the final statuses, the Groot2 publisher stops serving. A hook asked to
outlive the run decides so in its own ``close()``: the live viewer of ``--keep-serving`` shows
the end of the run and keeps serving until its ``stop()``.

The hooks of bt-manip: :class:`~bt_manip.viz.console.StatusLog` and
:class:`~bt_manip.viz.console.LiveTreeView` (console), :class:`~bt_manip.viz.live.LiveViewer`
(meshcat and the tree page), :class:`~bt_manip.viz.recorder.Recorder` (replay page),
:class:`~bt_manip.groot.GrootPublisher` (Groot2) and :class:`~bt_manip.groot.BtlogWriter`
(.btlog file). A plain callable (a function watching the run in a test) is a
:data:`TickCallback`: it is called after every tick and has nothing to close.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Protocol, TypeAlias, runtime_checkable

if TYPE_CHECKING:
    from bt_manip.run.runner import Runner


@runtime_checkable
class RunHook(Protocol):
    """Watches a run: called after each tick, closed once when the run has ended."""

    def __call__(self, runner: Runner) -> None:
        """After a tick: look at the run (the tree's statuses, the world, the sim time)."""
        ...

    def close(self) -> None:
        """The run has ended: finish (write files, stop servers). Idempotent."""
        ...


TickCallback: TypeAlias = "Callable[[Runner], None]"
"""A callable run after each tick that has nothing to close."""


def close_hooks(hooks: Iterable[RunHook | TickCallback]) -> None:
    """Close every :class:`RunHook` of ``hooks``, in order (plain callables have nothing to
    close). Every hook is closed even when one raises; the first error is raised after."""
    error: BaseException | None = None
    for hook in hooks:
        if not isinstance(hook, RunHook):
            continue
        try:
            hook.close()
        except BaseException as exc:  # close the others first
            if error is None:
                error = exc
    if error is not None:
        raise error
