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
