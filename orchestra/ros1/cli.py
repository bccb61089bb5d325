"""``orchestra env`` and ``orchestra run``: the ROS 1 layer for processes not started by a
launch, as shell lines (env) or for one package executable run in place (run, as rosrun)."""
from __future__ import annotations

import os
import shlex
import sys

import click

from orchestra.errors import OrchestraError
from orchestra.ros1.activation import ENV_VAR, MODES, layer_env


def env_lines(environ: dict[str, str], mode: str | None) -> list[str]:
    """``export NAME=value`` lines (POSIX shell quoting) for the layer's environment."""
    wanted = layer_env(environ)
    if mode is not None:
        wanted[ENV_VAR] = mode
    return [f"export {name}={shlex.quote(value)}" for name, value in sorted(wanted.items())]


@click.command("env")
@click.option("--mode", type=click.Choice(MODES), default=None,
              help=f"Also set {ENV_VAR} (default: leave it; 'auto' = the layer only without "
                   "a real rospy).")
def env(mode: str | None) -> None:
    """Print shell lines that give Python processes orchestra's ROS 1 layer.

    Use as: eval "$(orchestra env)"; then `python3 my_node.py` imports rospy, std_msgs.msg,
    my_pkg.msg... from orchestra unless a real rospy is importable (docs/rospy-layer.md).
    """
    for line in env_lines(dict(os.environ), mode):
        click.echo(line)


@click.command(context_settings={"ignore_unknown_options": True,
                                 "allow_interspersed_args": False})
@click.option("--prefix", default=None, metavar="CMD",
              help="Command to run the executable under, e.g. 'gdb -ex run --args'.")
@click.argument("package")
@click.argument("exe")
@click.argument("args", nargs=-1, type=click.UNPROCESSED)
def run(prefix: str | None, package: str, exe: str, args: tuple[str, ...]) -> None:
    """Run executable EXE of PACKAGE with ARGS (like rosrun).

    The executable replaces this process, so signals and the exit code are its own. A Python
    node gets orchestra's ROS 1 layer (rospy, <pkg>.msg...) unless a real rospy is
    importable, as under ``orchestra launch`` (docs/rospy-layer.md).
    """
    from orchestra.packages.executables import find_executable

    path = find_executable(package, exe)
    argv = (shlex.split(prefix) if prefix else []) + [path, *args]
    sys.stdout.flush()
    sys.stderr.flush()
    env = dict(os.environ)
    env.update(layer_env(env))
    try:
        os.execvpe(argv[0], argv, env)
    except OSError as exc:
        raise OrchestraError(f"cannot execute {argv[0]}: {exc.strerror}") from None
