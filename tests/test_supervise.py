"""The Supervisor with real child processes: respawn, backoff, required nodes, stopping, orphans.

Nodes are tiny /bin/sh or python scripts; nothing here needs a master or a launch file.
"""
from __future__ import annotations

import io
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import psutil
import pytest

from orchestra.supervise.output import Screen
from orchestra.supervise.process import OutputMode, ProcessSpec, RestartPolicy, State, restart_delay
from orchestra.supervise.reaper import setpriv_prefix
from orchestra.supervise.supervisor import Supervisor

pytestmark = pytest.mark.timeout(60)

FAST = RestartPolicy(backoff_initial=0.01, backoff_max=0.05, stable_after=10.0, crash_limit=0)


def sh(name: str, script: str, cwd: Path, **kw) -> ProcessSpec:
    kw.setdefault("output", OutputMode.SCREEN)
    return ProcessSpec(name, ("/bin/sh", "-c", script), dict(os.environ), str(cwd), **kw)


def py(name: str, code: str, cwd: Path, **kw) -> ProcessSpec:
    kw.setdefault("output", OutputMode.SCREEN)
    return ProcessSpec(name, (sys.executable, "-c", textwrap.dedent(code)),
                       dict(os.environ), str(cwd), **kw)


def quiet_screen() -> Screen:
    return Screen(out=io.BytesIO(), err=io.BytesIO(), colour=False)


def run(sup: Supervisor, until=None, limit: float = 20.0):
    """Run ``sup``; stop it once ``until()`` holds (checked every 20 ms) or after ``limit`` s."""
    deadline = time.monotonic() + limit

    def check() -> None:
        if sup.stopping:
            return
        if time.monotonic() > deadline:
            sup.request_stop("test limit reached", exit_code=99)
        elif until is not None and until():
            sup.request_stop("test condition met")
        else:
            sup.loop.call_later(0.02, check)

    sup.loop.call_later(0.02, check)
    return sup.run(install_signals=False)


def alive(pid: int) -> bool:
    try:
        proc = psutil.Process(pid)
        return proc.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def wait_dead(pids, limit: float = 5.0) -> list[int]:
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        left = [p for p in pids if alive(p)]
        if not left:
            return []
        time.sleep(0.05)
    return [p for p in pids if alive(p)]


# ---------------------------------------------------------------- restart rule (pure)

def test_restart_delay_first_failure_uses_respawn_delay_only():
    policy = RestartPolicy(backoff_initial=0.5, backoff_max=4, crash_limit=0)
    assert restart_delay(policy, 0.0, 1) == 0.0
    assert restart_delay(policy, 2.0, 1) == 2.0


def test_restart_delay_doubles_up_to_cap_and_never_below_respawn_delay():
    policy = RestartPolicy(backoff_initial=0.5, backoff_max=4, crash_limit=0)
    assert [restart_delay(policy, 0.0, n) for n in range(2, 8)] == [0.5, 1, 2, 4, 4, 4]
    assert restart_delay(policy, 3.0, 2) == 3.0


def test_restart_delay_gives_up_at_crash_limit():
    policy = RestartPolicy(crash_limit=3)
    assert restart_delay(policy, 0.0, 2) is not None
    assert restart_delay(policy, 0.0, 3) is None


# ---------------------------------------------------------------- respawn

def test_respawn_without_delay_restarts_and_cycles_states(tmp_path):
    marks = tmp_path / "starts"
    spec = sh("/crashy", f"echo x >> {marks}; exit 1", tmp_path, respawn=True)
    sup = Supervisor([spec], RestartPolicy(stable_after=0.0, crash_limit=0),
                     screen=quiet_screen())
    proc = sup.procs[0]
    result = run(sup, until=lambda: proc.restarts >= 5)
    assert result.exit_code == 0
    assert len(marks.read_text().split()) >= 5
    states = [s for _, s in proc.history]
    assert states[:4] == [State.RUNNING, State.BACKOFF, State.STARTING, State.RUNNING]


def test_respawn_honours_respawn_delay(tmp_path):
    marks = tmp_path / "starts"
    spec = sh("/slow", f"date +%s.%N >> {marks}; exit 0", tmp_path, respawn=True,
              respawn_delay=0.4)
    sup = Supervisor([spec], RestartPolicy(stable_after=0.0, crash_limit=0),
                     screen=quiet_screen())
    def third_start_written() -> bool:
        # RUNNING comes when the process is spawned; its `date` may not have run yet
        return marks.exists() and len(marks.read_text().split()) >= 3

    run(sup, until=lambda: sup.procs[0].restarts >= 2 and third_start_written())
    starts = [float(x) for x in marks.read_text().split()]
    assert len(starts) >= 3
    assert all(b - a >= 0.35 for a, b in zip(starts, starts[1:], strict=False))


def test_crash_loop_backs_off_to_failed_without_touching_other_nodes(tmp_path):
    policy = RestartPolicy(backoff_initial=0.01, backoff_max=0.05, crash_limit=4)
    specs = [sh("/steady", "sleep 100", tmp_path), sh("/loop", "exit 7", tmp_path, respawn=True)]
    sup = Supervisor(specs, policy, screen=quiet_screen())
    steady, loop = sup.procs
    steady_pid = []
    result = run(sup, until=lambda: loop.state == State.FAILED
                 and steady_pid.append(steady.pid) is None)
    assert loop.state == State.FAILED and loop.restarts == 3 and loop.exit_code == 7
    assert "crash loop" in loop.reason
    assert steady_pid == [steady.pid] and steady.restarts == 0
    assert [s for _, s in steady.history] == [State.RUNNING, State.STOPPING, State.EXITED]
    assert result.exit_code == 1 and result.failed == ["/loop"]


def test_stable_run_resets_the_crash_count(tmp_path):
    policy = RestartPolicy(backoff_initial=0.01, stable_after=0.2, crash_limit=2)
    spec = sh("/flaky", "sleep 0.3; exit 1", tmp_path, respawn=True)
    sup = Supervisor([spec], policy, screen=quiet_screen())
    run(sup, until=lambda: sup.procs[0].restarts >= 3)
    assert sup.procs[0].state == State.EXITED  # stopped by the test, never FAILED


# ---------------------------------------------------------------- required nodes

def test_required_node_death_stops_everything_with_nonzero_exit(tmp_path):
    specs = [sh("/other", "sleep 100", tmp_path),
             sh("/vital", "sleep 0.2; exit 3", tmp_path, required=True)]
    sup = Supervisor(specs, FAST, screen=quiet_screen())
    result = run(sup)
    assert result.exit_code == 1
    assert "/vital" in result.reason and "exit code 3" in result.reason
    other = sup.by_name("/other")
    assert other.state == State.EXITED and other.exit_code == -signal.SIGINT
    assert not alive(other.pid)


def test_required_node_spawn_failure_aborts_before_later_nodes(tmp_path):
    not_exec = tmp_path / "not_exec"
    not_exec.write_text("#!/bin/sh\nsleep 100\n")
    specs = [sh("/first", "sleep 100", tmp_path),
             ProcessSpec("/vital", (str(not_exec),), dict(os.environ), str(tmp_path),
                         required=True, location="demo.launch:4"),
             sh("/later", "sleep 100", tmp_path)]
    screen = quiet_screen()
    sup = Supervisor(specs, FAST, screen=screen)
    result = run(sup)
    assert result.exit_code == 1 and "/vital" in result.reason
    assert sup.by_name("/vital").state == State.FAILED
    assert sup.by_name("/later").pid is None
    assert sup.by_name("/first").state == State.EXITED and not alive(sup.by_name("/first").pid)
    assert b"demo.launch:4: cannot start /vital" in screen.err.getvalue()


def test_spawn_failure_of_optional_node_leaves_others_running(tmp_path):
    specs = [sh("/ok", "sleep 100", tmp_path),
             ProcessSpec("/broken", (str(tmp_path / "missing"),), dict(os.environ), str(tmp_path))]
    sup = Supervisor(specs, FAST, screen=quiet_screen())
    ok = sup.procs[0]
    result = run(sup, until=lambda: ok.state == State.RUNNING and ok.uptime > 0.2)
    assert sup.by_name("/broken").state == State.FAILED
    assert result.exit_code == 1 and result.failed == ["/broken"]


def test_nodes_sharing_a_missing_program_each_fail_and_a_new_cwd_is_made_once_per_batch(
        tmp_path):
    # a batch vets each (program, cwd, PATH) once: every node of it still gets the verdict
    missing = str(tmp_path / "missing")
    home = tmp_path / "home" / "deep"
    specs = [ProcessSpec(f"/broken{i}", (missing, f"__name:=b{i}"), dict(os.environ), str(home))
             for i in range(3)]
    specs.append(ProcessSpec("/ok", ("/bin/sh", "-c", "sleep 100"), dict(os.environ), str(home),
                             output=OutputMode.SCREEN))
    sup = Supervisor(specs, FAST, screen=quiet_screen())
    ok = sup.by_name("/ok")
    result = run(sup, until=lambda: ok.state == State.RUNNING and ok.uptime > 0.2)
    assert home.is_dir()
    assert sorted(result.failed) == ["/broken0", "/broken1", "/broken2"]
    for i in range(3):
        assert "No such file or directory" in sup.by_name(f"/broken{i}").reason


def test_all_nodes_finishing_ends_the_run_with_zero(tmp_path):
    sup = Supervisor([sh("/a", "exit 0", tmp_path), sh("/b", "exit 0", tmp_path)], FAST,
                     screen=quiet_screen())
    result = run(sup)
    assert result.exit_code == 0
    assert [p.state for p in sup.procs] == [State.EXITED, State.EXITED]


# ---------------------------------------------------------------- stopping

def test_node_ignoring_sigint_is_terminated_after_sigint_timeout(tmp_path):
    ready = tmp_path / "ready"
    code = f"""
        import signal, time, pathlib
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        pathlib.Path({str(ready)!r}).touch()
        time.sleep(100)
    """
    spec = py("/stubborn", code, tmp_path, sigint_timeout=0.3, sigterm_timeout=5)
    sup = Supervisor([spec], FAST, screen=quiet_screen())
    run(sup, until=ready.exists)
    proc = sup.procs[0]
    assert proc.exit_code == -signal.SIGTERM
    stop_at = next(t for t, s in proc.history if s == State.STOPPING)
    exit_at = next(t for t, s in proc.history if s == State.EXITED)
    assert 0.25 <= exit_at - stop_at < 5


def test_node_ignoring_sigint_and_sigterm_is_killed(tmp_path):
    ready = tmp_path / "ready"
    code = f"""
        import signal, time, pathlib
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        pathlib.Path({str(ready)!r}).touch()
        time.sleep(100)
    """
    spec = py("/deaf", code, tmp_path, sigint_timeout=0.2, sigterm_timeout=0.2)
    sup = Supervisor([spec], FAST, screen=quiet_screen())
    run(sup, until=ready.exists)
    assert sup.procs[0].exit_code == -signal.SIGKILL


def test_stop_goes_in_reverse_start_order(tmp_path):
    order = tmp_path / "order"
    specs = [sh(f"/n{i}", f"trap 'echo n{i} >> {order}; exit 0' INT; "
                          f"while :; do sleep 0.05; done", tmp_path)
             for i in range(3)]
    sup = Supervisor(specs, FAST, screen=quiet_screen())
    run(sup, until=lambda: all(p.uptime > 0.2 for p in sup.procs))
    stopping = [min(t for t, s in p.history if s == State.STOPPING) for p in sup.procs]
    assert stopping == sorted(stopping, reverse=True)
    assert sorted(order.read_text().split()) == ["n0", "n1", "n2"]


def test_grandchild_in_process_group_dies_with_node(tmp_path):
    pidfile = tmp_path / "gc.pid"
    spec = sh("/forker", f"sleep 1000 & echo $! > {pidfile}.tmp; mv {pidfile}.tmp {pidfile}; wait",
              tmp_path)
    sup = Supervisor([spec], FAST, screen=quiet_screen())
    run(sup, until=pidfile.exists)
    grandchild = int(pidfile.read_text())
    assert wait_dead([grandchild]) == []


def test_grandchild_that_left_the_group_dies_too(tmp_path):
    pidfile = tmp_path / "gc.pid"
    code = f"""
        import os, subprocess, time
        child = subprocess.Popen(["sleep", "1000"], start_new_session=True)
        with open({str(pidfile)!r} + ".tmp", "w") as fh:
            fh.write(str(child.pid))
        os.rename({str(pidfile)!r} + ".tmp", {str(pidfile)!r})
        time.sleep(100)
    """
    sup = Supervisor([py("/escaper", code, tmp_path)], FAST, screen=quiet_screen())
    run(sup, until=pidfile.exists)
    grandchild = int(pidfile.read_text())
    assert wait_dead([grandchild]) == []


def test_crashed_node_leaves_no_grandchild_behind(tmp_path):
    pidfile = tmp_path / "gc.pid"
    spec = sh("/crasher", f"sleep 1000 & echo $! > {pidfile}; exit 4", tmp_path)
    sup = Supervisor([spec, sh("/idle", "sleep 100", tmp_path)], FAST, screen=quiet_screen())
    run(sup, until=lambda: sup.procs[0].state == State.EXITED)
    assert wait_dead([int(pidfile.read_text())]) == []


# ---------------------------------------------------------------- output and logs

def test_screen_output_is_prefixed_with_node_name_and_keeps_last_line(tmp_path):
    screen = quiet_screen()
    spec = sh("/talker", "echo one; echo two; printf 'no newline'; echo oops >&2; exit 2",
              tmp_path)
    sup = Supervisor([spec], FAST, screen=screen)
    run(sup)
    out = screen.out.getvalue().decode()
    assert "[/talker] one\n[/talker] two\n[/talker] no newline\n" in out
    assert "[/talker] oops\n" in screen.err.getvalue().decode()


def test_log_files_complete_after_a_crash(tmp_path):
    logs = tmp_path / "logs"
    logs.mkdir()
    code = """
        import os, sys
        for i in range(5000):
            print("line %d" % i)
        sys.stdout.flush()
        sys.stderr.write("fatal: giving up\\n")
        sys.stderr.flush()
        os.kill(os.getpid(), 9)
    """
    screen = quiet_screen()
    spec = py("/crash", code, tmp_path, output=OutputMode.LOG, log_name="crash-1")
    sup = Supervisor([spec], FAST, screen=screen, log_dir=str(logs))
    run(sup)
    assert sup.procs[0].exit_code == -9
    lines = (logs / "crash-1-stdout.log").read_text().splitlines()
    assert lines == [f"line {i}" for i in range(5000)]
    assert (logs / "crash-1-stderr.log").read_text() == "fatal: giving up\n"
    # output="log": stdout only in the file, stderr on the console too (roslaunch rule)
    assert b"line 1" not in screen.out.getvalue()
    assert b"[/crash] fatal: giving up" in screen.err.getvalue()


def test_respawned_node_appends_to_its_log(tmp_path):
    spec = sh("/again", "echo run", tmp_path, respawn=True, output=OutputMode.BOTH,
              log_name="again-1")
    sup = Supervisor([spec], RestartPolicy(stable_after=0.0, crash_limit=0),
                     screen=quiet_screen(), log_dir=str(tmp_path))
    log = tmp_path / "again-1-stdout.log"
    # a restart is counted when it is spawned, before its output is in: wait for the text
    result = run(sup, until=lambda: log.exists() and log.read_text().count("run\n") >= 3)
    assert result.exit_code != 99, "three runs never reached the log"
    assert sup.procs[0].restarts >= 2


def test_log_file_rotates_by_size(tmp_path):
    spec = sh("/chatty", "i=0; while [ $i -lt 400 ]; do echo 0123456789012345678; i=$((i+1)); "
                         "done", tmp_path, output=OutputMode.LOG, log_name="chatty-1")
    sup = Supervisor([spec], FAST, screen=quiet_screen(), log_dir=str(tmp_path),
                     log_max_bytes=2000, log_backups=2)
    run(sup)
    files = sorted(p.name for p in tmp_path.glob("chatty-1-stdout.log*"))
    assert files == ["chatty-1-stdout.log", "chatty-1-stdout.log.1", "chatty-1-stdout.log.2"]
    assert all(p.stat().st_size <= 2000 for p in tmp_path.glob("chatty-1-stdout.log*"))


# ---------------------------------------------------------------- orchestra killed

WATCHED_RUN = """
import os, sys
from orchestra.supervise.process import ProcessSpec, RestartPolicy
from orchestra.supervise.reaper import Watchdog
from orchestra.supervise.supervisor import Supervisor
tmp, pdeathsig, with_watchdog = sys.argv[1], sys.argv[2], sys.argv[3] == "1"
watchdog = Watchdog() if with_watchdog else None
script = "sleep 1000 & echo $! > {0}/gc$N; echo $$ > {0}/n$N; wait".format(tmp)
specs = [ProcessSpec("/n%d" % i, ("/bin/sh", "-c", script), dict(os.environ, N=str(i)), tmp)
         for i in range(3)]
Supervisor(specs, RestartPolicy(), watchdog=watchdog, pdeathsig=pdeathsig).run()
"""


@pytest.mark.parametrize("pdeathsig, with_watchdog", [
    ("off", True),        # the watchdog alone kills every node's process group
    ("setpriv", False),   # the parent-death signal alone kills the nodes themselves
    ("preexec", False),
    ("auto", True),       # what orchestra launch uses
])
def test_sigkilled_orchestra_leaves_no_orphan(tmp_path, pdeathsig, with_watchdog):
    if pdeathsig == "setpriv":
        from orchestra.supervise.reaper import setpriv_prefix
        if setpriv_prefix() is None:
            pytest.skip("no setpriv with --pdeathsig on this machine")
    proc = subprocess.Popen([sys.executable, "-c", WATCHED_RUN, str(tmp_path), pdeathsig,
                             "1" if with_watchdog else "0"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    pids: list[int] = []
    try:
        deadline = time.monotonic() + 20
        names = [f"{k}{i}" for k in ("n", "gc") for i in range(3)]
        while not all((tmp_path / n).exists() and (tmp_path / n).read_text().strip()
                      for n in names):
            assert time.monotonic() < deadline, "nodes did not start"
            time.sleep(0.05)
        pids = [int((tmp_path / n).read_text()) for n in names]
        assert all(alive(p) for p in pids)
        proc.kill()
        proc.wait()
        must_die = pids if with_watchdog else pids[:3]
        assert wait_dead(must_die) == []
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for pid in pids:
            if alive(pid):
                os.kill(pid, signal.SIGKILL)


SLOW_SPAWN = """
import os, sys, time
from orchestra.supervise.reaper import MARK_VARIABLE, Watchdog
tmp = sys.argv[1]
watchdog = Watchdog()
if os.fork() == 0:   # a node caught between fork and exec, no parent-death signal yet
    with open(os.path.join(tmp, "late"), "w") as pid_file:   # the same pid after the exec
        pid_file.write(str(os.getpid()))
    time.sleep(0.4)
    os.execve("/bin/sh", ["sh", "-c", "exec sleep 1000"],
              dict(os.environ, **{MARK_VARIABLE: watchdog.mark}))
print("forked", flush=True)
time.sleep(1000)
"""


def test_a_node_that_execs_after_orchestra_was_killed_is_still_killed(tmp_path):
    """The parent-death signal is set after the fork (setpriv) and the mark is seen only
    after the exec, so a node being spawned when orchestra is SIGKILLed escaped both the
    signal and the watchdog's scan (a rosout left running by a killed ``orchestra core``).
    The node writes its pid before the exec: the watchdog may kill it as soon as it execs."""
    proc = subprocess.Popen([sys.executable, "-c", SLOW_SPAWN, str(tmp_path)],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    late = tmp_path / "late"
    try:
        assert proc.stdout.readline() == "forked\n"
        proc.kill()
        proc.wait()
        deadline = time.monotonic() + 10
        while not (late.exists() and late.read_text().strip()):
            assert time.monotonic() < deadline, "the late node never forked"
            time.sleep(0.02)
        assert wait_dead([int(late.read_text())]) == []
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        proc.stdout.close()
        if late.exists() and late.read_text().strip() and alive(int(late.read_text())):
            os.kill(int(late.read_text()), signal.SIGKILL)


def test_script_without_shebang_is_a_spawn_failure_in_every_mode(tmp_path):
    script = tmp_path / "noshebang"
    script.write_text("echo hi\n")
    script.chmod(0o755)
    for mode in ("setpriv", "preexec"):
        spec = ProcessSpec("/x", (str(script),), dict(os.environ), str(tmp_path))
        sup = Supervisor([spec], FAST, screen=quiet_screen(), pdeathsig=mode)
        run(sup)
        assert sup.procs[0].state == State.FAILED
        assert "Exec format error" in sup.procs[0].reason


def test_without_pidfd_a_waiter_thread_reports_exits(tmp_path, monkeypatch):
    from orchestra.supervise import supervisor as supervisor_module

    monkeypatch.setattr(supervisor_module, "_HAS_PIDFD", False)
    specs = [sh("/steady", "sleep 100", tmp_path),
             sh("/crashy", "echo bye; exit 2", tmp_path, respawn=True)]
    screen = quiet_screen()
    sup = Supervisor(specs, RestartPolicy(stable_after=0.0, crash_limit=0), screen=screen)
    result = run(sup, until=lambda: sup.procs[1].restarts >= 3)
    assert result.exit_code == 0
    assert sup.procs[0].state == State.EXITED and sup.procs[0].exit_code == -signal.SIGINT
    assert screen.out.getvalue().count(b"[/crashy] bye\n") >= 3


def test_spawner_gives_outcomes_in_call_order_with_errors_as_outcomes():
    from orchestra.supervise.spawner import Spawner

    def fail() -> int:
        raise OSError("no such program")

    spawner = Spawner(max_threads=4)
    try:
        outcomes = spawner.run([lambda: 1, fail, lambda: 3, lambda: 4, lambda: 5])
    finally:
        spawner.close()
    assert [o.value for o in outcomes] == [1, None, 3, 4, 5]
    assert isinstance(outcomes[1].error, OSError)
    assert [o.error for o in outcomes if o is not outcomes[1]] == [None] * 4


def test_spawner_runs_the_calls_itself_when_no_thread_can_start(monkeypatch):
    """RLIMIT_NPROC reached: the work already queued is done in the caller's thread."""
    from orchestra.supervise import spawner as spawner_module

    class NoThread(threading.Thread):
        def start(self) -> None:
            raise RuntimeError("can't start new thread")

    monkeypatch.setattr(spawner_module.threading, "Thread", NoThread)
    spawner = spawner_module.Spawner(max_threads=4)
    try:
        outcomes = spawner.run([threading.get_ident for _ in range(3)])
    finally:
        spawner.close()
    assert [o.value for o in outcomes] == [threading.get_ident()] * 3


@pytest.mark.skipif(not setpriv_prefix(), reason="util-linux setpriv --pdeathsig not available")
def test_processes_spawned_together_live_until_the_spawner_closes(tmp_path):
    """The parent-death signal follows the thread that forked a child: the spawner's threads
    must outlive what they started (and closing them is what a dead parent thread means)."""
    from orchestra.supervise.spawner import Spawner

    spawner = Spawner(max_threads=3)
    popens = spawner.run([
        lambda: subprocess.Popen([*setpriv_prefix(), "sleep", "30"], cwd=tmp_path)
        for _ in range(3)])
    procs = [outcome.value for outcome in popens]
    try:
        # setpriv has set the parent-death signal once it exec'd sleep
        deadline = time.monotonic() + 10
        while not all(_exe(proc.pid).endswith("/sleep") for proc in procs):
            assert time.monotonic() < deadline, "setpriv did not exec sleep"
            time.sleep(0.01)
        assert all(proc.poll() is None for proc in procs)
        spawner.close()      # the forking threads end: their children get SIGKILL
        for proc in procs:
            assert proc.wait(timeout=10) == -signal.SIGKILL
    finally:
        for proc in procs:
            proc.kill()
            proc.wait()


def _exe(pid: int) -> str:
    try:
        return os.readlink(f"/proc/{pid}/exe")
    except OSError:
        return ""
