""""Did you mean" for a mistyped name: packages, launch files, args, nodes.

One rule for every command (difflib's ratio, the three closest above 0.6), so suggestions
read the same everywhere. For graph names the last segment is matched too, so ``/talkr``
finds ``/robot1/talker``.
"""
from __future__ import annotations

from collections.abc import Iterable


def close_matches(word: str, choices: Iterable[str], limit: int = 3) -> list[str]:
    """The choices most like ``word`` (best first), an empty list when none is close."""
    import difflib  # only a miss pays for it: every launch imports this module

    options = sorted(set(choices))
    found = difflib.get_close_matches(word, options, n=limit, cutoff=0.6)
    if not found and "/" in word:
        by_base: dict[str, list[str]] = {}
        for choice in options:
            by_base.setdefault(choice.rsplit("/", 1)[-1], []).append(choice)
        for base in difflib.get_close_matches(word.rsplit("/", 1)[-1], list(by_base),
                                              n=limit, cutoff=0.6):
            found += by_base[base]
    return found[:limit]


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """`` (did you mean a, b?)`` for the close matches of ``word``, or ``""``."""
    found = close_matches(word, choices)
    return f" (did you mean {', '.join(found)}?)" if found else ""
