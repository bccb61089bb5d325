"""turtle_teleop_key as a process: arrow keys through a real pseudo-terminal drive turtle1,
'q' quits cleanly and restores the terminal, and without a terminal it exits 0 at once."""
from __future__ import annotations

import os
import pty
import signal
import subprocess
import sys
import termios
import time
from pathlib import Path

import pytest

# orchestra's bundled packages, whatever ROS workspace the developer's shell points at
BUNDLED_ENV = {k: v for k, v in os.environ.items()
               if k not in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH")}

SCRIPTS = Path(__file__).resolve().parent.parent / "packages" / "turtlesim" / "scripts"

READ_X = r'''
import orchestra.node as node
from orchestra.node.msg import get_message_class
node.init_node("teleop_test_reader", anonymous=True)
m = node.wait_for_message("/turtle1/pose", get_message_class("turtlesim/Pose"), timeout=20)
print(m.x)
'''


@pytest.fixture
def master():
    from orchestra.master import start_master
    handle = start_master(port=0)
    yield handle.uri
    handle.shutdown()


def stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def turtle_x(env: dict) -> float:
    out = subprocess.run([sys.executable, "-c", READ_X], env=env, capture_output=True,
                         text=True, timeout=30)
    assert out.returncode == 0, out.stderr
    return float(out.stdout.strip().splitlines()[-1])


@pytest.mark.timeout(60)
def test_teleop_without_a_terminal_exits_zero_with_a_reason(master):
    env = dict(BUNDLED_ENV, ROS_MASTER_URI=master)
    proc = subprocess.run([str(SCRIPTS / "turtle_teleop_key")], env=env, stdin=subprocess.DEVNULL,
                          capture_output=True, text=True, timeout=30)
    assert proc.returncode == 0
    assert "not a terminal" in proc.stdout + proc.stderr


@pytest.mark.timeout(60)
def test_teleop_up_arrow_in_a_terminal_moves_turtle1_forward_and_q_quits(master):
    env = dict(BUNDLED_ENV, ROS_MASTER_URI=master, PYTHONUNBUFFERED="1")
    env.pop("DISPLAY", None)
    sim = subprocess.Popen([str(SCRIPTS / "turtlesim_node")], env=env,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    controller, terminal = pty.openpty()
    saved = termios.tcgetattr(terminal)
    teleop = subprocess.Popen([str(SCRIPTS / "turtle_teleop_key")], env=env, stdin=terminal,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        start = turtle_x(env)
        # up arrow: 2 m/s (scale_linear) for 1 s; pressed three times because the first may
        # go out before teleop's publisher is connected on a busy machine
        for _ in range(3):
            time.sleep(0.7)
            os.write(controller, b"\x1b[A")
        time.sleep(1.5)
        moved = turtle_x(env) - start
        assert 1.0 < moved < 5.5
        os.write(controller, b"q")
        assert teleop.wait(10) == 0
        assert termios.tcgetattr(terminal)[3] == saved[3]  # local modes restored
    finally:
        stop(teleop)
        stop(sim)
        os.close(controller)
        os.close(terminal)
