"""Monte-Carlo runs of a tree: many seeded episodes in parallel, with statistics.

``bt-manip bench TREE --world W --runs N --seed S [--inject ...] [--jobs J] [--out DIR]`` runs
episodes with seeds S, S+1, ..., S+N-1 (each seed draws the world's randomised starts and the
injected faults), in J worker processes, and reports:

- the success rate with a 95 % Wilson score interval;
- sim time, wall time (building the world and loading the tree included) and real-time factor
  per episode (mean, median, 95th percentile);
- failures counted by node and reason (the node whose failure ended each failed episode);
- the actions that failed during episodes, and in how many episodes: the failures the tree
  recovered from (or did not), for instance how often a recovery branch was needed
  (conditions are left out: their failures are how a tree decides, not trouble).

It writes ``episodes.json``, ``episodes.csv``, ``summary.json`` and ``outcomes.png`` to DIR.

Modules, each importing only those above it:

- :mod:`~bt_manip.bench.episodes`: one episode run and condensed (:class:`EpisodeResult`,
  :func:`run_one`), and the version of the output formats;
- :mod:`~bt_manip.bench.stats`: statistics over the episodes (:class:`BenchSummary`);
- :mod:`~bt_manip.bench.ray`: the episodes as Ray tasks (``--backend ray``);
- :mod:`~bt_manip.bench.pool`: running a bench's episodes, here or in worker processes, with
  its progress;
- :mod:`~bt_manip.bench.files`: episodes.json, episodes.csv, summary.json and outcomes.png;
- :mod:`~bt_manip.bench.log`: episodes.jsonl, written as episodes finish, read back to resume;
- :mod:`~bt_manip.bench.sweep`: one bench per value of a fault or blackboard entry;
- :mod:`~bt_manip.bench.points`: the benches one command runs, new or resumed, each with its
  log.

The ``bench`` verb's arguments are in :mod:`bt_manip.cli.bench`.
"""
