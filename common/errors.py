"""Errors that carry where bad input came from, so the CLI can print ``file:line: reason``."""
from __future__ import annotations

from os import PathLike


class CassiInputError(ValueError):
    """Bad user input: a malformed file, an unknown name, an invalid option.

    The CLI maps it to exit code 2 and prints ``str(err)``, which reads
    ``path:line: reason`` when a path (and line) is known.
    """

    def __init__(self, reason: str, *, path: str | PathLike | None = None, line: int | None = None):
        self.reason = reason
        self.path = None if path is None else str(path)
        self.line = line
        super().__init__(self._format())

    def _format(self) -> str:
        if self.path is None:
            return self.reason
        if self.line is None:
            return f"{self.path}: {self.reason}"
        return f"{self.path}:{self.line}: {self.reason}"


def first_few(items: list[str], n: int = 6) -> str:
    """The first ``n`` of ``items`` "; "-separated, and how many more: a message names what
    went wrong without growing with a night's thousands of jobs."""
    return "; ".join(items[:n]) + (f"; and {len(items) - n} more" if len(items) > n else "")
