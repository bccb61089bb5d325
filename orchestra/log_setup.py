"""How every orchestra command logs: one ``logging`` set-up for the click group and for the
command lines run without click (``orchestra/cli.py``), so both log alike."""
from __future__ import annotations


def configure_logging(verbose: int) -> None:
    """Warnings and errors on stderr; ``-v`` adds info, ``-vv`` debug."""
    import logging  # here, not at import time: ``orchestra --help`` does not need it

    level = logging.WARNING - 10 * min(verbose, 2)
    logging.basicConfig(level=level, format="[%(levelname)s] %(name)s: %(message)s")
