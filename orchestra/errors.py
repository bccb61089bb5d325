"""User-facing errors.

Anything a user can cause (a bad launch file, an unknown package, a bad YAML value) raises an
``OrchestraError`` subclass carrying a location; the CLI turns it into ``file:line: message``
on stderr and a non-zero exit code, never a traceback.
"""
from __future__ import annotations

from dataclasses import dataclass

# A value quoted in a message is cut to this many characters: a 1 MB attribute must not make
# a 1 MB error line. Whole messages are cut at MAX_MESSAGE as a backstop.
MAX_QUOTED = 200
MAX_MESSAGE = 2000


def clip(text: str, limit: int = MAX_QUOTED) -> str:
    """``text``, or its first ``limit`` characters and a note of its full length."""
    if len(text) <= limit:
        return text
    return f"{text[:limit]}... ({len(text)} chars)"


@dataclass(frozen=True, init=False)
class Location:
    """Where something was written: a file and, when known, a line and column."""

    file: str
    line: int | None = None
    column: int | None = None

    def __init__(self, file: str, line: int | None = None, column: int | None = None):
        # Frozen: the fields are written once, here, straight into the instance's dict. The
        # generated __init__ of a frozen dataclass goes through object.__setattr__ per field,
        # twice the cost, and every element of every launch file read gets a Location.
        fields = self.__dict__
        fields["file"] = file
        fields["line"] = line
        fields["column"] = column

    def __str__(self) -> str:
        text = self.file
        if self.line is not None:
            text += f":{self.line}"
            if self.column is not None:
                text += f":{self.column}"
        return text


def offset_location(file: str, text: str | bytes, offset: int) -> Location:
    """The line and column (1-based) of character/byte ``offset`` of ``text``.

    For errors that only report an offset: a decoding error, a YAML reader error.
    """
    offset = max(0, min(offset, len(text)))
    newline = "\n" if isinstance(text, str) else b"\n"
    line = text.count(newline, 0, offset) + 1  # type: ignore[arg-type]
    start = text.rfind(newline, 0, offset) + 1  # type: ignore[arg-type]
    return Location(file, line, offset - start + 1)


class OrchestraError(Exception):
    """Base class of every error that is the user's to fix. ``exit_code`` is what the CLI returns."""

    exit_code = 2

    def __init__(self, message: str, location: Location | None = None):
        message = clip(message, MAX_MESSAGE)
        super().__init__(message)
        self.message = message
        self.location = location

    def __str__(self) -> str:
        if self.location is not None:
            return f"{self.location}: {self.message}"
        return self.message
