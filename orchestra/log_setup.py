"""How every orchestra command logs: one ``logging`` set-up for the click group and for the
command lines run without click (``orchestra/cli.py``), so both log alike.

The print-and-exit command lines (``orchestra launch --dump-params`` ...) mostly log nothing,
and importing ``logging`` (with ``traceback``, ``string``, ``threading``) is ~18 M
instructions, a tenth of such a process's own work (issue 15). So the modules they run log
through ``logger()``, which imports ``logging`` when something is first logged, and those
command lines set logging up only then (``configure_logging(..., deferred=True)``).
"""
from __future__ import annotations

import sys
from typing import TYPE_CHECKING, cast

if TYPE_CHECKING:
    import logging

#: the verbosity of a deferred ``configure_logging``, set up at the first ``logger()`` use
_deferred: list[int] = []


def configure_logging(verbose: int, *, deferred: bool = False) -> None:
    """Warnings and errors on stderr; ``-v`` adds info, ``-vv`` debug. ``deferred``: when
    ``logging`` is first used through ``logger()`` (for command lines whose modules all log
    through it), not now."""
    if deferred and "logging" not in sys.modules:
        _deferred[:] = [verbose]
        return
    _deferred.clear()
    _basic_config(verbose)


def _basic_config(verbose: int) -> None:
    import logging  # here, not at import time: ``orchestra --help`` does not need it

    level = logging.WARNING - 10 * min(verbose, 2)
    logging.basicConfig(level=level, format="[%(levelname)s] %(name)s: %(message)s")


def logger(name: str) -> logging.Logger:
    """``logging.getLogger(name)``, imported and looked up when first used (a module's
    ``log = logger(__name__)`` at import time costs nothing)."""
    return cast("logging.Logger", _LazyLogger(name))


class _LazyLogger:
    """Stands for ``logging.getLogger(name)``: every attribute is the real logger's."""

    __slots__ = ("_name", "_logger")

    def __init__(self, name: str):
        self._name = name
        self._logger: logging.Logger | None = None

    def __getattr__(self, attr: str) -> object:
        real = self._logger
        if real is None:
            import logging

            if _deferred:
                _basic_config(_deferred.pop())
            real = self._logger = logging.getLogger(self._name)
        return getattr(real, attr)
