"""``orchestra logs [NODE] [-f]``: the run's log directory (roslaunch-logs) and a node's tail."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import free_port, wait_for  # noqa: E402

pytestmark = pytest.mark.timeout(90)


def test_logs_prints_the_run_directory_and_tails_a_node(tmp_path):
    pkg = tmp_path / "ws" / "demo"
    (pkg / "nodes").mkdir(parents=True)
    (pkg / "package.xml").write_text(
        "<package format='2'><name>demo</name><version>0.0.0</version><description>d"
        "</description><maintainer email='a@b.c'>a</maintainer><license>BSD</license></package>")
    (pkg / "nodes" / "talker").write_text(
        "#!/bin/sh\ni=0\nwhile true; do i=$((i+1)); echo \"tick $i\"; sleep 0.1; done\n")
    (pkg / "nodes" / "talker").chmod(0o755)
    (tmp_path / "x.launch").write_text(
        '<launch><group ns="r1"><node pkg="demo" type="talker" name="talker"/></group></launch>')
    env = {k: v for k, v in os.environ.items() if k not in ("ROS_LOG_DIR", "ROS_NAMESPACE")}
    env.update(ROS_PACKAGE_PATH=str(tmp_path / "ws"), ROS_HOME=str(tmp_path / "home"),
               ROS_MASTER_URI=f"http://localhost:{free_port()}/", XDG_RUNTIME_DIR=str(tmp_path))

    def orchestra(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "orchestra", *args], env=env,
                              capture_output=True, text=True, timeout=60)

    launch = subprocess.Popen([sys.executable, "-m", "orchestra", "launch",
                               str(tmp_path / "x.launch"), "--no-status", "--no-rosout"],
                              env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        wait_for(lambda: orchestra("logs").returncode == 0, timeout=30)
        log_dir = Path(orchestra("logs").stdout.strip())
        assert log_dir.parent == tmp_path / "home" / "log"
        wait_for(lambda: "tick 3" in orchestra("logs", "/r1/talker", "-n", "5").stdout)
        tail = orchestra("logs", "r1/talker", "-n", "2").stdout.splitlines()
        assert "==> " + str(log_dir / "r1-talker-1-stdout.log") + " <==" in tail
        assert sum(line.startswith("tick ") for line in tail) == 2
        follow = subprocess.Popen([sys.executable, "-m", "orchestra", "logs", "/r1/talker",
                                   "-f", "-n", "0"], env=env, stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True)
        try:
            lines = [follow.stdout.readline() for _ in range(6)]
            assert sum("] tick " in line for line in lines) >= 3   # new lines as they come
        finally:
            follow.send_signal(signal.SIGINT)
            _, err = follow.communicate(timeout=20)
        assert "Traceback" not in err and "Aborted" not in err
        wrong = orchestra("logs", "/r1/talkr")
        assert wrong.returncode == 2 and "(did you mean /r1/talker?)" in wrong.stderr
    finally:
        launch.send_signal(signal.SIGINT)
        launch.wait(timeout=30)
