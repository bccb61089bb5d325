"""Shell completion (bash, zsh, fish) through click's completion: commands, packages, launch
files, launch args (``name:=``) and the node names of the running launch.

``orchestra completion bash`` prints the script to source (docs/completion.md). The functions
here are click ``shell_complete`` callbacks: they run in the shell's completion call, so
they must be quick and must never fail (a broken launch file completes nothing).
"""
from __future__ import annotations

import os
from typing import TYPE_CHECKING

import click

if TYPE_CHECKING:
    from click.shell_completion import CompletionItem

# click.shell_completion is imported by the callbacks, not here: every `orchestra launch`
# imports this module to name its callback, and the import is ~2.5 ms of its start-up.

LAUNCH_SUFFIXES = (".launch", ".launch.xml", ".launch.yaml", ".launch.yml")


def _is_launch_file(name: str) -> bool:
    return name.endswith(LAUNCH_SUFFIXES) or (name.endswith((".xml", ".yaml", ".yml"))
                                              and name != "package.xml")


def _package_launch_files(package: str) -> list[str]:
    from orchestra.packages import find_package

    root = find_package(package)
    found = []
    for _, dirnames, files in os.walk(root):
        dirnames[:] = [d for d in dirnames if not d.startswith(".")]
        found += [f for f in files if _is_launch_file(f)]
    return sorted(set(found))


def _local_paths(incomplete: str) -> list[str]:
    """Launch files and directories next to what is typed (``launch/x.la<TAB>``)."""
    folder, _, start = incomplete.rpartition("/")
    where = folder or "."
    try:
        entries = sorted(os.scandir(where), key=lambda e: e.name)
    except OSError:
        return []
    prefix = folder + "/" if folder else ""
    return [prefix + e.name + ("/" if e.is_dir() else "") for e in entries
            if e.name.startswith(start) and not e.name.startswith(".")
            and (e.is_dir() or _is_launch_file(e.name))]


def _launch_file(words: list[str]) -> str | None:
    """The launch file the words typed so far name (``PKG FILE`` or a path), if any."""
    positional = [w for w in words if ":=" not in w]
    if positional and os.path.isfile(positional[0]):
        return positional[0]
    if len(positional) >= 2:
        from orchestra.launch.load import find_in_package

        return find_in_package(positional[0], positional[1])
    return None


def complete_launch_words(ctx: click.Context, param: click.Parameter,
                          incomplete: str) -> list[CompletionItem]:
    """``orchestra launch [PKG] FILE [name:=value ...]``, word by word."""
    from click.shell_completion import CompletionItem

    try:
        words = list(ctx.params.get(param.name or "", None) or ())
        positional = [w for w in words if ":=" not in w]
        if not positional:
            from orchestra.packages import get_index

            packages = [p for p in get_index().packages if p.startswith(incomplete)]
            return [CompletionItem(p) for p in sorted(packages)] + \
                [CompletionItem(p, type="file") for p in _local_paths(incomplete)]
        if len(positional) == 1 and not os.path.isfile(positional[0]):
            return [CompletionItem(f) for f in _package_launch_files(positional[0])
                    if f.startswith(incomplete)]
        path = _launch_file(words)
        if path is None:
            return []
        from orchestra.launch.declared_args import declared_args
        from orchestra.launch.interpreter import parse_launch_file

        given = {w.split(":=", 1)[0] for w in words if ":=" in w}
        return [CompletionItem(f"{a.name}:=", help=a.doc or None)
                for a in declared_args(parse_launch_file(path), path)
                if a.name.startswith(incomplete) and a.name not in given]
    except Exception:  # noqa: BLE001 - completion must never break the shell
        return []


def complete_node_names(ctx: click.Context, param: click.Parameter,
                        incomplete: str) -> list[CompletionItem]:
    """Node names of the orchestra launch at ROS_MASTER_URI."""
    from click.shell_completion import CompletionItem

    try:
        from orchestra.master import master_uri_from_env
        from orchestra.supervise.status import launches_at

        names = {n["name"] for launch in launches_at(master_uri_from_env())
                 for n in launch["nodes"]}
        typed = incomplete if incomplete.startswith("/") or not incomplete else "/" + incomplete
        return [CompletionItem(n) for n in sorted(names) if n.startswith(typed)]
    except Exception:  # noqa: BLE001 - completion must never break the shell
        return []


@click.command()
@click.argument("shell", type=click.Choice(["bash", "zsh", "fish"]))
def completion(shell: str) -> None:
    """Print the shell completion script for SHELL (bash, zsh or fish).

    Load it from the shell's start-up file, e.g. ``eval "$(orchestra completion bash)"``.
    """
    from click.shell_completion import get_completion_class

    root = click.get_current_context().find_root().command
    cls = get_completion_class(shell)
    assert cls is not None
    click.echo(cls(root, {}, "orchestra", "_ORCHESTRA_COMPLETE").source())
