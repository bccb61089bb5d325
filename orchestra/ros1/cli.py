"""``orchestra env``: shell lines that give a shell's Python processes the ROS 1 layer."""
from __future__ import annotations

import os
import shlex

import click

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
