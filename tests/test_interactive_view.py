"""``orchestra launch --ui`` driven in a real terminal (tmux): select, restart, mute, log,
filter, quit; and the key parser on its own."""
from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from orchestra.supervise.interactive import parse_keys

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import demo_package, free_port, wait_for  # noqa: E402

pytestmark = pytest.mark.timeout(90)

LAUNCH = """<launch>
  <node pkg="demo" type="talker" name="a" output="screen"/>
  <node pkg="demo" type="sleeper" name="b"/>
  <group ns="cam"><node pkg="demo" type="sleeper" name="c"/></group>
</launch>
"""


def test_key_bytes_become_key_names():
    assert parse_keys(b"\x1b[A\x1b[Bjk/cam\r\x7f\x1b\x1b[Cq") == [
        "up", "down", "j", "k", "/", "c", "a", "m", "enter", "backspace", "esc", "q"]


class Pane:
    """One tmux session running a command in a 110x35 terminal."""

    def __init__(self, name: str, command: str):
        self.name = name
        subprocess.run(["tmux", "new-session", "-d", "-s", name, "-x", "110", "-y", "35",
                        command], check=True)

    def text(self) -> str:
        return subprocess.run(["tmux", "capture-pane", "-p", "-t", self.name],
                              capture_output=True, text=True).stdout

    def keys(self, *keys: str) -> None:
        subprocess.run(["tmux", "send-keys", "-t", self.name, *keys], check=True)

    def close(self) -> None:
        subprocess.run(["tmux", "kill-session", "-t", self.name], capture_output=True)


@pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")
def test_interactive_view_select_restart_mute_filter_quit(tmp_path):
    pkg = demo_package(tmp_path / "ws", {
        "sleeper": "#!/bin/sh\nexec sleep 1000\n",
        "talker": "#!/bin/sh\ni=0\nwhile true; do i=$((i+1)); echo \"tick $i\"; sleep 0.2; done\n"})
    (tmp_path / "ui.launch").write_text(LAUNCH)
    env = {"PYTHONPATH": os.environ.get("PYTHONPATH", ""), "ROS_PACKAGE_PATH": str(pkg.parent),
           "ROS_MASTER_URI": f"http://localhost:{free_port()}/",
           "ROS_HOME": str(tmp_path / "home"), "XDG_RUNTIME_DIR": str(tmp_path)}
    launch = shlex.join(["env", *(f"{k}={v}" for k, v in env.items()), sys.executable, "-m",
                         "orchestra", "launch", str(tmp_path / "ui.launch"), "--ui",
                         "--no-rosout", "--no-summary"])
    pane = Pane(f"orchestra-ui-{os.getpid()}", f"{launch}; echo EXITED rc=$?; sleep 60")

    def status() -> dict:
        out = subprocess.run([sys.executable, "-m", "orchestra", "status", "--json"],
                             env=dict(os.environ, **env), capture_output=True, text=True).stdout
        docs = json.loads(out) if out.strip() else []
        return {n["name"]: n for n in docs[0]["nodes"]} if docs else {}

    try:
        wait_for(lambda: "> /a " in pane.text() and pane.text().count("RUNNING") == 3,
                 timeout=30)
        before = status()
        pane.keys("Down")                                      # select /b
        wait_for(lambda: "> /b " in pane.text())
        pane.keys("r")                                         # restart it
        wait_for(lambda: status()["/b"]["pid"] not in (None, before["/b"]["pid"])
                 and status()["/b"]["state"] == "RUNNING")
        assert status()["/a"]["pid"] == before["/a"]["pid"]
        assert "restarting /b" in pane.text()

        pane.keys("Up", "m", "l")                              # mute /a, show its log
        wait_for(lambda: "muted" in pane.text() and "last output of /a" in pane.text())

        def ticks() -> tuple[int, int]:
            """(last tick scrolled on screen, last tick in the log panel)."""
            text = pane.text()
            screen = [int(n) for n in re.findall(r"\[/a\] tick (\d+)", text)]
            panel = [int(n) for n in re.findall(r"^tick (\d+)", text, re.M)]
            return max(screen or [0]), max(panel or [0])

        wait_for(lambda: ticks()[1] >= ticks()[0] + 5)         # runs on, shown no more
        pane.keys("/", "c", "a", "m", "Enter")                 # filter by name
        wait_for(lambda: "[filter: cam]" in pane.text() and "> /cam/c " in pane.text())
        assert " /b " not in pane.text().split("NODE", 1)[1]
        capture = pane.text()
        pane.keys("q")                                         # quit: clean stop
        wait_for(lambda: "EXITED rc=0" in pane.text(), timeout=30)
        assert "q pressed in the interactive view; all processes stopped" in pane.text()
    finally:
        pane.close()
    print(capture)
