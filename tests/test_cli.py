"""The top-level command: help lists the areas, errors are one line and a non-zero exit."""
import subprocess
import sys


def run(*args):
    return subprocess.run([sys.executable, "-m", "orchestra", *args],
                          capture_output=True, text=True, timeout=60)


def test_help_shows_usage():
    proc = run("--help")
    assert proc.returncode == 0
    assert "Usage" in proc.stdout


def test_unknown_command_is_an_error_without_traceback():
    proc = run("no-such-command")
    assert proc.returncode != 0
    assert "Traceback" not in proc.stderr


def test_command_table_help_is_each_commands_own_help():
    """``orchestra --help`` lists the table's help lines without importing the commands, so
    each line must be the command's own first docstring sentence (click's short help)."""
    from orchestra.commands import COMMANDS, LazyGroup

    for name, (_, help_line) in COMMANDS.items():
        command = LazyGroup._load(name)
        assert command is not None
        assert command.get_short_help_str(limit=10_000) == help_line, name


def test_help_imports_no_sub_command():
    code = ("import sys; from orchestra.cli import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            "loaded = sorted(m for m in sys.modules if m.startswith('orchestra.')"
            " and m not in ('orchestra.cli', 'orchestra.commands', 'orchestra.errors',"
            " 'orchestra.log_setup'))\n"
            "print(loaded, 'logging' in sys.modules, 'yaml' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert proc.stdout.strip().endswith("[] False False"), proc.stdout + proc.stderr


def test_no_help_shows_the_docstrings_rest_literal_markup():
    """``orchestra export --help`` showed ````local````: the docstrings' markup leaked."""
    import click

    from orchestra.commands import COMMANDS, cli

    def helps(command, path):
        with click.Context(command, info_name=" ".join(path)) as ctx:
            yield " ".join(path), command.get_help(ctx)
            if isinstance(command, click.Group):
                for name in command.list_commands(ctx):
                    yield from helps(command.get_command(ctx, name), [*path, name])

    with click.Context(cli) as ctx:
        pages = dict(item for name in COMMANDS
                     for item in helps(cli.get_command(ctx, name), ["orchestra", name]))
    assert "orchestra node stop" in pages and "orchestra export" in pages
    assert [path for path, text in pages.items() if "``" in text] == []
