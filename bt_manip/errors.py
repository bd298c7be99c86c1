"""Errors caused by the user's input (trees, worlds, arguments).

Loaders collect every problem they find as a :class:`Problem` and raise one
:class:`InputError` carrying all of them. The CLI prints each as ``file:line: message`` and
exits with code 2, without a traceback.
"""

from __future__ import annotations

from dataclasses import dataclass, field

MAX_MESSAGE = 1000
"""Characters of a problem's message printed at most."""


@dataclass(frozen=True)
class Problem:
    """One thing wrong with an input file: where, and what (and what would be right)."""

    file: str
    line: int | None
    message: str
    column: int | None = None

    def __str__(self) -> str:
        message = self.message
        if len(message) > MAX_MESSAGE:  # a huge value quoted in a message is cut short
            message = message[:MAX_MESSAGE] + " ... (cut short)"
        where = self.file
        if self.line is not None:
            where += f":{self.line}"
            if self.column is not None:
                where += f":{self.column}"
        return f"{where}: {message}"


@dataclass
class InputError(Exception):
    """Bad user input; carries every problem found. Maps to exit code 2."""

    problems: list[Problem] = field(default_factory=list)

    def __post_init__(self) -> None:
        super().__init__(str(self))

    def __str__(self) -> str:
        return "\n".join(str(p) for p in self.problems)

    @classmethod
    def single(cls, file: str, line: int | None, message: str) -> InputError:
        return cls([Problem(file, line, message)])
