"""One run of a tree: the loop, what it reports, and the services it gives the tree.

- :mod:`~bt_manip.run.runner`: :class:`~bt_manip.run.runner.Runner`, the tick/step loop, and
  its :class:`~bt_manip.run.runner.RunOptions`;
- :mod:`~bt_manip.run.status`: :class:`~bt_manip.run.status.RunStatus`, how a run ended, and
  the exit codes of ``bt-manip run``;
- :mod:`~bt_manip.run.hooks`: :class:`~bt_manip.run.hooks.RunHook`, what watches a run (live
  views, recorders, the Groot2 publisher), owned and closed by the runner;
- :mod:`~bt_manip.run.report`: the run report (``--report``) and its console summary;
- :mod:`~bt_manip.run.failure_cause`: the failure that ended a run;
- :mod:`~bt_manip.run.context`: :class:`~bt_manip.run.context.RunContext`, a run's typed
  services (clock, world, faults, overlay, each robot's navigator and IK);
- :mod:`~bt_manip.run.faults`: seeded fault injection (``--inject``);
- :mod:`~bt_manip.run.interrupts`: SIGTERM ends a run as Ctrl-C does.

:mod:`bt_manip.episode` wires them into one run (world, tree, context, runner). This package's
``__init__`` imports nothing, so that reading an exit code does not load the simulator.
"""
