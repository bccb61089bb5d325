"""The ``orchestra`` entry point: user mistakes become one clear line on stderr and exit
code 2, whichever way a command line is read.

Command lines are parsed and run by click (``orchestra.commands``), except those made only of
``orchestra launch``'s print-and-exit options and launch words (``--dump-params``,
``--nodes``...): tools run those hundreds of times, and importing click is a fifth of their
time, so ``orchestra.app.launch_output`` reads them from the same option table the click
command is built from and runs them without click. Anything it does not read exactly as
click would goes to click.
"""
from __future__ import annotations

import sys

from orchestra.errors import OrchestraError


def main(argv: list[str] | None = None) -> None:
    """Run the command line ``argv`` and exit with its code; without ``argv``, this process's
    own command line (the console script, ``python -m orchestra``), which ends with it."""
    args = sys.argv[1:] if argv is None else list(argv)
    try:
        rv = _run(args, whole_process=argv is None)
    except OrchestraError as exc:
        import click

        click.echo(f"orchestra: error: {exc}", err=True)
        sys.exit(exc.exit_code)
    except KeyboardInterrupt:
        sys.exit(130)
    except BrokenPipeError:
        sys.exit(1)
    sys.exit(rv if isinstance(rv, int) else 0)


def _run(args: list[str], *, whole_process: bool) -> object:
    if args[:1] == ["launch"]:
        from orchestra.app.launch_output import parse_output_request, run_output_request

        request = parse_output_request(args[1:])
        if request is not None:
            from orchestra.log_setup import configure_logging

            if whole_process:
                _short_lived()
            # what the click group does without -v, when something logs: the modules these
            # lines run log through log_setup.logger(), so most of them import no logging
            configure_logging(0, deferred=True)
            run_output_request(request)
            return None
    from orchestra.commands import run

    return run(args)


def _short_lived() -> None:
    """This process prints and exits: no garbage collector. It makes next to no cyclic
    garbage (a 1,000-node tree peaks at the same RSS without the collector), while the
    collector's passes over the growing heap are ~5 % of a one-node dump and ~18 % of a
    1,000-node one; and what it holds at exit is frozen, so the interpreter's exit does not
    search it for garbage either (~10 % of a one-node dump)."""
    import atexit
    import gc

    gc.disable()
    atexit.register(gc.freeze)
