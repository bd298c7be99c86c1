"""Differential testing of bt-manip against the real BehaviorTree.CPP 4.8.2.

Random trees of BT.CPP built-ins are ticked on both engines with the same schedule and the
runs are compared step by step. The pieces:

- :mod:`.spec`: a case (main tree, subtrees, initial typed entries, schedule) and its XML;
- :mod:`.leaf`: the stateful test leaf ``TestLeaf`` both engines register, its behaviour
  encoded in its name;
- :mod:`.generator`: seeded random cases over every built-in;
- :mod:`.oracle` / :mod:`.oracle_worker`: BT.CPP (``behaviortreepy``) in a worker process;
- :mod:`.btmanip_runner`: the same case on bt-manip's public API;
- :mod:`.compare`: what is compared and how values are normalised;
- :mod:`.rules`: the named exclusions, each citing ``docs/btcpp-differences.md``;
- :mod:`.shrink`: reduction of a mismatching case to a minimal one;
- :mod:`.causes`: names for the causes of mismatches, to group reports;
- :mod:`.campaign`: running many cases, figures, shrunk mismatches, report files.

Entry points: ``tests/bt/test_differential.py`` (``BTM_DIFF_TREES``, ``BTM_DIFF_SEED``) and
``benchmarks/btcpp_differential.py``.
"""
