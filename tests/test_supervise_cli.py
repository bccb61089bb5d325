"""``orchestra launch FILE`` as a user runs it: signals to orchestra, SIGKILL, exit codes."""
from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

pytestmark = pytest.mark.timeout(90)

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import demo_package, free_port, wait_for_cpu  # noqa: E402

NODE = """#!/bin/sh
# a node that forks a helper (same process group), records both pids, and waits
sleep 1000 &
echo "$$ $!" > "$PIDS_DIR/$1"
trap 'kill $! 2>/dev/null; exit 0' INT TERM
wait
"""

LAUNCH = """<launch>
  <node pkg="demo" type="forker" name="a" args="a"/>
  <group ns="g">
    <node pkg="demo" type="forker" name="b" args="b" output="screen"/>
  </group>
  <node pkg="demo" type="forker" name="c" args="c" respawn="true"/>
</launch>
"""


@pytest.fixture
def launch_env(tmp_path):
    pkg = demo_package(tmp_path / "ws", {"forker": NODE})
    (pkg / "launch").mkdir()
    (pkg / "launch" / "demo.launch").write_text(LAUNCH)
    pids = tmp_path / "pids"
    pids.mkdir()
    env = {k: v for k, v in os.environ.items()
           if k not in ("ROS_LOG_DIR", "ROS_NAMESPACE", "CMAKE_PREFIX_PATH")}
    env.update(ROS_PACKAGE_PATH=str(tmp_path / "ws"), ROS_HOME=str(tmp_path / "home"),
               ROS_MASTER_URI=f"http://localhost:{free_port()}/", PIDS_DIR=str(pids),
               XDG_RUNTIME_DIR=str(tmp_path))
    return {"env": env, "launch": str(pkg / "launch" / "demo.launch"), "pids": pids,
            "tmp": tmp_path}


def start(launch_env, *extra):
    return subprocess.Popen(
        [sys.executable, "-m", "orchestra", "launch", launch_env["launch"], "--no-status",
         *extra], env=launch_env["env"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True)


def wait_pids(launch_env, proc, names=("a", "b", "c")) -> list[int]:
    deadline = time.monotonic() + 30
    files = [launch_env["pids"] / n for n in names]
    while not all(f.exists() and len(f.read_text().split()) == 2 for f in files):
        if proc.poll() is not None or time.monotonic() > deadline:
            out, err = proc.communicate(timeout=10) if proc.poll() is None else proc.communicate()
            pytest.fail(f"nodes did not start (exit {proc.returncode}): {err[-2000:]}")
        time.sleep(0.05)
    return [int(p) for f in files for p in f.read_text().split()]


def alive(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def survivors(pids, limit=5.0) -> list[int]:
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline and any(alive(p) for p in pids):
        time.sleep(0.05)
    return [p for p in pids if alive(p)]


@contextlib.contextmanager
def running(launch_env, *extra):
    """``orchestra launch`` of the test's launch file; killed on the way out if still running."""
    proc = start(launch_env, *extra)
    try:
        yield proc
    finally:
        if proc.poll() is None:
            proc.kill()
        if proc.stdout is not None and not proc.stdout.closed:
            proc.communicate()


def finish(proc, sig: int | None = None) -> tuple[str, str]:
    """Send ``sig`` to orchestra (if given), wait for its exit, return (stdout, stderr)."""
    if sig is not None:
        proc.send_signal(sig)
    return proc.communicate(timeout=30)


def test_sigkilled_orchestra_launch_leaves_no_node_or_grandchild(launch_env):
    with running(launch_env) as proc:
        pids = wait_pids(launch_env, proc)
        proc.kill()
        proc.wait(timeout=10)
        assert survivors(pids) == []


DETACHER = """#!/bin/sh
# a node that starts a helper in a session of its own (out of reach of its process group),
# records both pids once the helper is in its session, then waits -- or, with "exit",
# leaves the helper behind at once
setsid sh -c 'echo $$ > "$0"; exec sleep 1000' "$PIDS_DIR/$1.helper" &
while [ ! -s "$PIDS_DIR/$1.helper" ]; do sleep 0.05; done
echo "$$ $(cat "$PIDS_DIR/$1.helper")" > "$PIDS_DIR/$1"
[ "$2" = exit ] && exit 0
trap 'exit 0' INT TERM
wait
"""


def add_detacher(launch_env, args: str) -> None:
    node = Path(launch_env["launch"]).parent.parent / "nodes" / "detacher"
    node.write_text(DETACHER)
    node.chmod(0o755)
    Path(launch_env["launch"]).write_text(
        f'<launch><node pkg="demo" type="detacher" name="d" args="{args}"/></launch>')


def test_sigkilled_orchestra_leaves_no_grandchild_that_called_setsid(launch_env):
    add_detacher(launch_env, "d")
    with running(launch_env) as proc:
        node, helper = wait_pids(launch_env, proc, names=("d",))
        assert os.getsid(helper) != os.getsid(node)      # really out of the node's session
        proc.kill()
        proc.wait(timeout=10)
        assert survivors([node, helper]) == []


def test_stop_ends_what_an_exited_node_left_outside_its_process_group(launch_env):
    add_detacher(launch_env, "d exit")
    with running(launch_env) as proc:
        node, helper = wait_pids(launch_env, proc, names=("d",))
        assert survivors([node]) == []        # the node is gone: its helper is an orphan
        assert alive(helper)
        out, err = finish(proc, signal.SIGINT)
    assert proc.returncode == 0, err
    assert survivors([helper], limit=3) == []
    assert f"{helper} (sleep)" in err and "outside their process groups" in err


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
def test_stop_signal_to_orchestra_is_a_graceful_stop(launch_env, sig):
    with running(launch_env) as proc:
        pids = wait_pids(launch_env, proc)
        out, err = finish(proc, sig)
    assert proc.returncode == 0, err
    assert survivors(pids, limit=1) == []
    assert f"{signal.Signals(sig).name} received" in err
    # output="screen" node lines are on orchestra's stdout, prefixed
    assert "process[/g/b]: started with pid" in out


def test_required_node_death_via_cli_exit_code(launch_env):
    Path(launch_env["launch"]).write_text(
        LAUNCH.replace('name="a" args="a"', 'name="a" args="a" required="true"'))
    with running(launch_env) as proc:
        pids = wait_pids(launch_env, proc)
        os.kill(pids[0], signal.SIGKILL)     # node /a (required) dies
        out, err = finish(proc)
    assert proc.returncode == 1
    assert "required process /a died (killed by SIGKILL)" in err
    assert survivors(pids, limit=2) == []


def test_log_files_named_like_roslaunch_with_latest_link(launch_env):
    with running(launch_env) as proc:
        wait_pids(launch_env, proc)
        finish(proc, signal.SIGINT)
    latest = launch_env["tmp"] / "home" / "log" / "latest"
    names = sorted(p.name for p in latest.iterdir() if p.name != "rosout.log")
    # output="log" nodes get files; the output="screen" node /g/b does not; /rosout, started
    # with the embedded master as roslaunch starts roscore's, counts first
    assert names == ["a-2-stderr.log", "a-2-stdout.log", "c-4-stderr.log", "c-4-stdout.log",
                     "rosout-1-stderr.log", "rosout-1-stdout.log"]


def test_wait_flag_waits_for_an_external_master_and_uses_it(launch_env):
    import xmlrpc.client

    from orchestra.master import port_from_uri, start_master

    proc = start(launch_env, "--wait")
    master = None
    try:
        deadline = time.monotonic() + 20
        while b"waiting for the master" not in _peek_stderr(proc):
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        assert list(launch_env["pids"].iterdir()) == []      # nothing started meanwhile
        master = start_master("127.0.0.1", port_from_uri(launch_env["env"]["ROS_MASTER_URI"]))
        pids = wait_pids(launch_env, proc)
        with xmlrpc.client.ServerProxy(master.uri) as proxy:
            code, _, run_id = proxy.getParam("/t", "/run_id")
        assert code == 1 and run_id
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
        assert proc.returncode == 0, err
        assert "started embedded master" not in err
        assert survivors(pids, limit=1) == []
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
        if master is not None:
            master.shutdown()


_STDERR: dict[int, bytes] = {}


def _peek_stderr(proc) -> bytes:
    """What the process wrote to stderr so far (non-blocking; kept for communicate())."""
    import fcntl

    fd = proc.stderr.fileno()
    flags = fcntl.fcntl(fd, fcntl.F_GETFL)
    fcntl.fcntl(fd, fcntl.F_SETFL, flags | os.O_NONBLOCK)
    try:
        chunk = os.read(fd, 65536)
    except BlockingIOError:
        chunk = b""
    finally:
        fcntl.fcntl(fd, fcntl.F_SETFL, flags)
    _STDERR[proc.pid] = _STDERR.get(proc.pid, b"") + chunk
    return _STDERR[proc.pid]


def test_output_both_writes_the_console_and_the_log_file(launch_env):
    """output="both" (an orchestra extension, as ROS 2's launch): stdout lines reach the
    console, prefixed, and the node's log file."""
    Path(launch_env["launch"]).write_text(
        '<launch>\n  <node pkg="demo" type="talker" name="t" output="both"/>\n</launch>\n')
    talker = Path(launch_env["launch"]).parent.parent / "nodes" / "talker"
    talker.write_text("#!/bin/sh\necho both-line\ntrap 'exit 0' INT TERM\n"
                      "while :; do sleep 0.2; done\n")
    talker.chmod(0o755)
    log_dir = launch_env["tmp"] / "home" / "log" / "latest"
    with running(launch_env) as proc:
        deadline = time.monotonic() + 30
        while not any("both-line" in p.read_text() for p in log_dir.glob("t-*-stdout.log")):
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.05)
        out, err = finish(proc, signal.SIGINT)
    assert proc.returncode == 0, err
    assert "[/t] both-line" in out


def _python_start_up_interrupted(err: str) -> bool:
    """The Ctrl-C came while the interpreter was still starting, before any orchestra code
    could own it: in ``site`` (this machine's .pth hooks take ~20 ms of CPU), runpy, or the
    package's first line. Python reports the KeyboardInterrupt itself (or fails to import
    site) and exits; nothing was started. Any frame of an orchestra module but the package's
    ``__init__`` means orchestra code was running: that is not this case."""
    frames = re.findall(r'File "([^"]+)"', err)
    ours = [f for f in frames if os.sep + "orchestra" + os.sep in f
            and not f.endswith(os.path.join("orchestra", "__init__.py"))]
    return "KeyboardInterrupt" in err and bool(frames) and not ours


@pytest.mark.parametrize("moment", [0.0, 0.03, 0.06, 0.09, 0.12])
def test_ctrl_c_in_the_launchs_first_moments_always_ends_it(launch_env, moment):
    """Found sending Ctrl-C within 0.2 s of start: ~2 in 30 launches ran on, the
    KeyboardInterrupt dropped inside an import-lock callback. SIGINT after the process has
    used ``moment`` s of CPU (a whole start-up takes ~0.17 s: importing, resolving,
    starting), three times each."""
    for _ in range(3):
        with running(launch_env) as proc:
            wait_for_cpu(proc, moment)
            proc.send_signal(signal.SIGINT)
            out, err = proc.communicate(timeout=30)
        pids = [int(p) for f in launch_env["pids"].iterdir() for p in f.read_text().split()]
        if _python_start_up_interrupted(err):
            assert proc.returncode != 0, err
        else:
            # -SIGINT: before Python's own handler existed; 130: during the imports; 0: stopped
            assert proc.returncode in (-signal.SIGINT, 130, 0), err
            assert "Traceback" not in err and "Exception ignored" not in err, err
        assert survivors(pids) == []
