"""The ``orchestra`` click group, whose sub-commands live next to their library.

Sub-commands are imported lazily (only the one that runs is imported), because
``orchestra launch --dump-plan`` is called hundreds of times by tools and its start-up time
is part of the product. Each area owns its own ``cli`` module; this file only lists them.
The entry point (``orchestra.cli:main``) imports this module for every command line it does
not run without click.
"""
from __future__ import annotations

import importlib
import sys

import click

from orchestra.log_setup import configure_logging

# name -> ("module:attribute" of a click command or group, its one-line help). The help is
# here so that ``orchestra --help`` lists the commands without importing any of them
# (tests/test_cli.py checks it against each command's own docstring).
COMMANDS: dict[str, tuple[str, str]] = {
    "launch": ("orchestra.app.cli:launch",
               "Resolve and run a roslaunch file: orchestra launch [PKG] FILE [name:=value ...]."),
    "check": ("orchestra.app.checkcli:check",
              "Report every problem in launch files (and what they include), starting nothing."),
    "convert": ("orchestra.launch.tools_cli:convert",
                "Convert a launch file (or every launch file under a directory) between XML and "
                "YAML."),
    "export": ("orchestra.export.cli:export",
               "Write a launch file as units for another process manager (see docs/remote.md)."),
    "pkg": ("orchestra.packages.cli:pkg", "Find packages and their dependencies (like rospack)."),
    "run": ("orchestra.ros1.cli:run", "Run executable EXE of PACKAGE with ARGS (like rosrun)."),
    "create-pkg": ("orchestra.packages.cli:create_pkg",
                   "Create catkin package NAME depending on DEPS (like catkin_create_pkg)."),
    "core": ("orchestra.app.cli:core",
             "Run a ROS master, parameter server and the rosout node until interrupted."),
    "param": ("orchestra.params.cli:param",
              "Get, set, list, delete, load and dump parameters (rosparam compatible)."),
    "status": ("orchestra.app.cli:status",
               "Show the nodes of the running launch: state, pid, restarts, uptime, CPU%, RSS, "
               "and why a node is not running."),
    "logs": ("orchestra.app.logs:logs",
             "Without NODE: the log directory of the run at ROS_MASTER_URI (roslaunch-logs)."),
    "completion": ("orchestra.completion:completion",
                   "Print the shell completion script for SHELL (bash, zsh or fish)."),
    "test": ("orchestra.app.cli:test_command",
             "Run a launch file's <test>s as rostest does: orchestra test [PKG] FILE "
             "[name:=value ...]."),
    "node": ("orchestra.app.nodecli:node",
             "Running nodes: list, info, kill, ping, cleanup (like rosnode); loggers and "
             "set-logger-level (like rosconsole list/get/set)."),
    "topic": ("orchestra.node.cli:topic",
              "Topics: list, find, info, type, echo, pub, hz (like rostopic)."),
    "service": ("orchestra.node.cli:service",
                "Services: list, info, type, uri, args, call (like rosservice)."),
    "graph": ("orchestra.node.cli:graph", "Draw the running nodes and the topics between them."),
    "bag": ("orchestra.bag.cli:bag", "Record, play and inspect ROS 1 bags (rosbag)."),
    "plot": ("orchestra.plot.cli:plot",
             "Plot numeric fields: TOPIC/FIELD, several fields as TOPIC/F1:F2 (as rqt_plot)."),
    "env": ("orchestra.ros1.cli:env",
            "Print shell lines that give Python processes orchestra's ROS 1 layer."),
    "msg": ("orchestra.node.msgcli:msg",
            "Message types (like rosmsg): show, md5, list, package, packages."),
    "srv": ("orchestra.node.msgcli:srv",
            "Service types (like rossrv): show, md5, list, package, packages."),
}


def _short_help(text: str, limit: int) -> str:
    """The first sentence of ``text``, cut at a word to ``limit`` characters with "...".

    Written here because click 8.5 deprecates its own ``make_default_short_help``.
    """
    first = text.split(". ")[0].rstrip(".")
    if len(first) <= limit:
        return first
    cut = first[: max(limit - 3, 1)].rsplit(" ", 1)[0]
    return cut + "..."


class LazyGroup(click.Group):
    """A click group that imports a sub-command's module only when that command is used;
    its help lists the commands from the table, importing none of them."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(COMMANDS)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        return self._load(cmd_name)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        names = self.list_commands(ctx)
        limit = formatter.width - 6 - max(len(name) for name in names)
        rows = [(name, _short_help(COMMANDS[name][1], limit)) for name in names]
        with formatter.section("Commands"):
            formatter.write_dl(rows)

    @staticmethod
    def _load(name: str) -> click.Command | None:
        entry = COMMANDS.get(name)
        if entry is None:
            return None
        module_name, attr = entry[0].split(":")
        command = getattr(importlib.import_module(module_name), attr)
        assert isinstance(command, click.Command)
        _plain_help(command)
        return command


def _plain_help(command: click.Command) -> None:
    """Drop the docstrings' reST literal markup (````name````) from the help of ``command``,
    its options and sub-commands: the docstrings are written for the code's readers and
    double as ``--help``, where the backticks would only be noise. Here once, for every
    command, rather than in each docstring."""
    for attr in ("help", "short_help", "epilog"):
        text = getattr(command, attr, None)
        if text:
            setattr(command, attr, text.replace("``", ""))
    for param in command.params:
        text = getattr(param, "help", None)
        if text:
            param.help = text.replace("``", "")   # type: ignore[attr-defined]
    if isinstance(command, click.Group):
        for sub in command.commands.values():
            _plain_help(sub)


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="orchestra")
@click.option("-v", "--verbose", count=True, help="More log output (-vv for debug).")
def cli(verbose: int) -> None:
    """roslaunch-compatible launch orchestration: same launch files, no ROS install."""
    configure_logging(verbose)


def run(args: list[str]) -> object:
    """Parse and run ``args`` with click: the command's return value; click's own exceptions
    end the process as click's standalone mode would, except that Ctrl-C exits quietly."""
    try:
        return cli.main(args=args, prog_name="orchestra", standalone_mode=False)
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
