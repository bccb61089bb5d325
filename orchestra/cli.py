"""The ``orchestra`` command: one click group whose sub-commands live next to their library.

Sub-commands are imported lazily (only the one that runs is imported), because
``orchestra launch --dump-plan`` is called hundreds of times by tools and its start-up time
is part of the product. Each area owns its own ``cli`` module; this file only lists them.
"""
from __future__ import annotations

import importlib
import logging
import sys

import click

from orchestra.errors import OrchestraError

# name -> "module:attribute" of a click command or group
COMMANDS: dict[str, str] = {
    "launch": "orchestra.app.cli:launch",
    "check": "orchestra.launch.tools_cli:check",
    "convert": "orchestra.launch.tools_cli:convert",
    "export": "orchestra.export.cli:export",
    "pkg": "orchestra.packages.cli:pkg",
    "run": "orchestra.packages.cli:run",
    "create-pkg": "orchestra.packages.cli:create_pkg",
    "core": "orchestra.app.cli:core",
    "param": "orchestra.params.cli:param",
    "status": "orchestra.app.cli:status",
    "logs": "orchestra.app.logs:logs",
    "test": "orchestra.app.cli:test_command",
    "node": "orchestra.node.cli:node",
    "topic": "orchestra.node.cli:topic",
    "service": "orchestra.node.cli:service",
    "graph": "orchestra.node.cli:graph",
    "bag": "orchestra.bag.cli:bag",
    "plot": "orchestra.plot.cli:plot",
    "env": "orchestra.ros1.cli:env",
    "msg": "orchestra.node.msgcli:msg",
    "srv": "orchestra.node.msgcli:srv",
}


class LazyGroup(click.Group):
    """A click group that imports a sub-command's module only when that command is used."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(name for name in COMMANDS if self._load(name) is not None)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        return self._load(cmd_name)

    @staticmethod
    def _load(name: str) -> click.Command | None:
        target = COMMANDS.get(name)
        if target is None:
            return None
        module_name, attr = target.split(":")
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            # an area not built yet: its commands are simply not offered
            if exc.name and module_name.startswith(exc.name):
                return None
            raise
        return getattr(module, attr, None)


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="orchestra")
@click.option("-v", "--verbose", count=True, help="More log output (-vv for debug).")
def cli(verbose: int) -> None:
    """roslaunch-compatible launch orchestration: same launch files, no ROS install."""
    level = logging.WARNING - 10 * min(verbose, 2)
    logging.basicConfig(level=level, format="[%(levelname)s] %(name)s: %(message)s")


def main(argv: list[str] | None = None) -> None:
    """Entry point: user mistakes become one clear line on stderr and exit code 2."""
    try:
        rv = cli.main(args=argv, prog_name="orchestra", standalone_mode=False)
    except OrchestraError as exc:
        click.echo(f"orchestra: error: {exc}", err=True)
        sys.exit(exc.exit_code)
    except click.exceptions.Abort as exc:
        # Ctrl-C is how long-running commands (topic hz/echo, launch) are ended: quietly,
        # as the ROS tools do; "Aborted." is for a declined prompt
        if not isinstance(exc.__cause__, KeyboardInterrupt):
            click.echo("Aborted.", err=True)
        sys.exit(130)
    except click.ClickException as exc:
        exc.show()
        sys.exit(exc.exit_code)
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except KeyboardInterrupt:
        sys.exit(130)
    except BrokenPipeError:
        sys.exit(1)
    sys.exit(rv if isinstance(rv, int) else 0)
