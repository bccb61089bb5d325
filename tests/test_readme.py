"""The README's command table names every command and sub-command the CLI offers."""
from __future__ import annotations

import re
from pathlib import Path

import click
import pytest

from orchestra.commands import cli

README = (Path(__file__).resolve().parent.parent / "README.md").read_text(encoding="utf-8")
CTX = click.Context(cli)


def _groups() -> list[tuple[str, click.Group]]:
    found = []
    for name in cli.list_commands(CTX):
        command = cli.get_command(CTX, name)
        if isinstance(command, click.Group):
            found.append((name, command))
    return found


@pytest.mark.parametrize("name", cli.list_commands(CTX))
def test_readme_mentions_every_command(name):
    assert f"orchestra {name}" in README


@pytest.mark.parametrize("group,command", _groups(), ids=[g for g, _ in _groups()])
def test_readme_lists_every_sub_command_in_its_groups_rows(group, command):
    rows = " ".join(line for line in README.splitlines() if f"`orchestra {group} " in line)
    missing = [sub for sub in command.list_commands(CTX)
               if not re.search(rf"[ |`\\]{re.escape(sub)}[\\|` ]", rows)]
    assert not missing, f"README's `orchestra {group}` rows do not name {missing}"
