"""``orchestra convert``: a launch-file tool that never starts anything.

(``orchestra check`` is composed a layer up, in app/checkcli.py: its ``--check-machines``
reaches the remote machines.)
"""
from __future__ import annotations

import os
import sys

import click

from orchestra.errors import OrchestraError
from orchestra.launch import convert as conversion


@click.command()
@click.argument("path", type=click.Path(exists=True, dir_okay=True))
@click.option("--to", "fmt", type=click.Choice(conversion.FORMATS), required=True,
              help="Target syntax.")
@click.option("-o", "--output", type=click.Path(dir_okay=False, writable=True),
              help="Write the converted file here (single file only; default: stdout).")
def convert(path: str, fmt: str, output: str | None) -> None:
    """Convert a launch file (or every launch file under a directory) between XML and YAML.

    A FILE is converted to stdout (or -o OUT); its includes are left as written, since XML
    and YAML launch files may include each other. A DIRECTORY is converted in place: each
    launch file gets a sibling (x.launch -> x.launch.yaml, x.launch.yaml -> x.launch) and
    includes of files converted in the same run are pointed at the new names.
    """
    if os.path.isdir(path):
        if output:
            raise click.UsageError("-o/--output takes a single file; a directory is "
                                   "converted in place")
        done = conversion.convert_tree(path, fmt)
        for item in done:
            click.echo(f"{item.source} -> {item.target}")
        click.echo(f"converted {len(done)} launch file(s)", err=True)
        return
    text = conversion.convert_file(path, fmt)
    if output:
        try:
            with open(output, "w", encoding="utf-8") as fh:
                fh.write(text)
        except OSError as exc:
            raise OrchestraError(f"cannot write {output}: {exc.strerror}") from None
    else:
        sys.stdout.write(text)
