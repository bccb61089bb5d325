"""Shell completion through click: commands, packages, launch files, launch args, scripts."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

REPO_PACKAGES = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                             "packages")


def complete(*words: str, env: dict[str, str] | None = None) -> list[str]:
    """What bash gets offered for the last of ``words`` (``""``: a new word)."""
    environ = dict(env or os.environ, _ORCHESTRA_COMPLETE="bash_complete",
                   COMP_WORDS=" ".join(("orchestra",) + words), COMP_CWORD=str(len(words)))
    out = subprocess.run([sys.executable, "-m", "orchestra"], env=environ,
                         capture_output=True, text=True, timeout=60).stdout
    return [line.split(",", 1)[1] for line in out.splitlines() if "," in line]


def test_commands_complete():
    assert complete("la") == ["launch"]
    assert "logs" in complete("lo")


@pytest.mark.parametrize("words, expected", [
    (("learn",), ["learning_tf"]),
    (("learning_tf", "start_tf"), ["start_tf_demo.launch", "start_tf_demo_py.launch"]),
    (("learning_tf", "start_tf_demo.launch", "dr"), ["driver:="]),
    (("learning_tf", "start_tf_demo.launch", "driver:=auto", ""), ["snapshot:="]),
])
def test_launch_completes_packages_launch_files_and_args(words, expected):
    assert complete("launch", *words) == expected


def test_launch_completes_local_launch_files(tmp_path):
    (tmp_path / "here.launch").write_text("<launch/>")
    (tmp_path / "notes.txt").write_text("")
    (tmp_path / "sub").mkdir()
    env = dict(os.environ, ROS_PACKAGE_PATH=str(tmp_path / "none"))
    old = os.getcwd()
    os.chdir(tmp_path)
    try:
        offered = complete("launch", "", env=env)
    finally:
        os.chdir(old)
    assert "here.launch" in offered and "sub/" in offered and "notes.txt" not in offered


@pytest.mark.parametrize("shell", ["bash", "zsh", "fish"])
def test_completion_script_for_each_shell(shell):
    cli = subprocess.run([sys.executable, "-m", "orchestra", "completion", shell],
                         capture_output=True, text=True, timeout=60)
    assert cli.returncode == 0 and "_ORCHESTRA_COMPLETE" in cli.stdout
