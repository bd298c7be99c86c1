"""How a run ended (:class:`RunStatus`) and the exit code of ``bt-manip run`` for each.

Exit codes (:data:`EXIT_CODES`): 0 root SUCCESS, 1 root FAILURE, root SKIPPED or budget spent,
2 bad input (including a tree that breaks while running: a script error, a port without a
value), 130 interrupted.
"""

from __future__ import annotations

from enum import Enum

EXIT_SUCCESS = 0
EXIT_FAILURE = 1
EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130


class RunStatus(str, Enum):
    """How a run ended. A string: the run report's JSON, bench's files and the console show
    its value (``str()`` and ``format()`` give ``SUCCESS``, not ``RunStatus.SUCCESS``), and it
    compares equal to that value."""

    SUCCESS = "SUCCESS"
    """The root returned SUCCESS."""
    FAILURE = "FAILURE"
    """The root returned FAILURE."""
    SKIPPED = "SKIPPED"
    """Every node the root would run was skipped by a pre-condition."""
    BUDGET = "BUDGET"
    """The tick or sim-time budget was spent first; the tree was halted."""
    ERROR = "ERROR"
    """The tree broke while running (a script error, a port without a value); halted."""
    INTERRUPTED = "INTERRUPTED"
    """Ctrl-C (or SIGTERM); the tree was halted."""

    def __str__(self) -> str:
        return self.value

    def __format__(self, spec: str) -> str:
        return format(self.value, spec)

    @property
    def exit_code(self) -> int:
        """The exit code of ``bt-manip run`` for a run that ended so."""
        return EXIT_CODES[self]


EXIT_CODES: dict[RunStatus, int] = {
    RunStatus.SUCCESS: EXIT_SUCCESS,
    RunStatus.FAILURE: EXIT_FAILURE,
    RunStatus.SKIPPED: EXIT_FAILURE,
    RunStatus.BUDGET: EXIT_FAILURE,
    RunStatus.ERROR: EXIT_BAD_INPUT,
    RunStatus.INTERRUPTED: EXIT_INTERRUPTED,
}
"""The exit code of each way a run can end (keys compare equal to their string values)."""
