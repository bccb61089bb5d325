"""User-facing errors.

Anything a user can cause (a bad launch file, an unknown package, a bad YAML value) raises an
``OrchestraError`` subclass carrying a location; the CLI turns it into ``file:line: message``
on stderr and a non-zero exit code, never a traceback.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Location:
    """Where something was written: a file and, when known, a line and column."""

    file: str
    line: int | None = None
    column: int | None = None

    def __str__(self) -> str:
        text = self.file
        if self.line is not None:
            text += f":{self.line}"
            if self.column is not None:
                text += f":{self.column}"
        return text


class OrchestraError(Exception):
    """Base class of every error that is the user's to fix. ``exit_code`` is what the CLI returns."""

    exit_code = 2

    def __init__(self, message: str, location: Location | None = None):
        super().__init__(message)
        self.message = message
        self.location = location

    def __str__(self) -> str:
        if self.location is not None:
            return f"{self.location}: {self.message}"
        return self.message
