"""The run loop, under its former name: :mod:`bt_manip.run` holds it now.

``from bt_manip.runner import Runner, RunOptions`` goes on working; new code imports from
:mod:`bt_manip.run.runner`, :mod:`bt_manip.run.report` and :mod:`bt_manip.run.status`.
"""

from __future__ import annotations

from bt_manip.run.hooks import RunHook, TickCallback
from bt_manip.run.report import REPORT_SCHEMA_VERSION, NodeReport, RunReport, node_reports
from bt_manip.run.runner import MAX_PACING_LAG, Runner, RunOptions, TickableTree
from bt_manip.run.status import (
    EXIT_BAD_INPUT,
    EXIT_CODES,
    EXIT_FAILURE,
    EXIT_INTERRUPTED,
    EXIT_SUCCESS,
    RunStatus,
)

__all__ = [
    "EXIT_BAD_INPUT", "EXIT_CODES", "EXIT_FAILURE", "EXIT_INTERRUPTED", "EXIT_SUCCESS",
    "MAX_PACING_LAG", "REPORT_SCHEMA_VERSION", "NodeReport", "RunHook", "RunOptions",
    "RunReport", "RunStatus", "Runner", "TickCallback", "TickableTree", "node_reports",
]
