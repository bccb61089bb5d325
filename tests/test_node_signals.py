"""Signals reaching a node or a tool: the handler runs between two bytecodes of whatever the
main thread was doing, so it must neither take a lock that thread may hold nor raise inside
the unwinding of an earlier signal."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import xmlrpc.client
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import wait_for  # noqa: E402

pytestmark = pytest.mark.timeout(90)


def test_node_signal_handler_takes_no_lock_the_interrupted_thread_holds(monkeypatch):
    """Two SIGINTs arriving while the main thread is inside a sleep's ``Condition.wait``
    (holding the shutdown event's lock): the handler may not wait for that lock."""
    from orchestra.node import context, runtime

    rt = runtime.NodeRuntime("/n", "/", "http://127.0.0.1:9/", {}, "127.0.0.1", [])
    monkeypatch.setattr(context, "_current", rt)
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        runtime._install_signal_handlers()
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    monkeypatch.setitem(runtime._previous_handlers, signal.SIGINT, signal.default_int_handler)
    raised: list[BaseException] = []

    def interrupted_thread() -> None:
        with rt._shutdown_requested._cond:       # what Event.wait holds around its wait
            try:
                runtime._on_signal(signal.SIGINT, None)
                runtime._on_signal(signal.SIGINT, None)
            except BaseException as exc:  # noqa: BLE001 - the test reports any of them
                raised.append(exc)

    thread = threading.Thread(target=interrupted_thread, daemon=True)
    thread.start()
    thread.join(10)
    assert not thread.is_alive(), "the signal handler waited for a lock its thread holds"
    assert raised == []
    wait_for(rt.is_shutdown)
    rt.wait_shutdown_done(10)
    assert rt.cleanup_finished


def test_a_tools_second_sigint_does_not_interrupt_the_first_ones_unwinding():
    from orchestra.node import tool

    with pytest.raises(KeyboardInterrupt):
        tool._interrupt_once(signal.SIGINT, None)
    tool._interrupt_once(signal.SIGINT, None)   # returns: the tool is already on its way out


def _chatter_published(uri: str) -> bool:
    with xmlrpc.client.ServerProxy(uri) as master:
        publishers = master.getSystemState("/probe")[2][0]
    return any(topic == "/chatter" for topic, _ in publishers)


def test_two_sigints_back_to_back_end_topic_pub_cleanly(master):
    env = dict(os.environ, ROS_MASTER_URI=master.uri, PYTHONUNBUFFERED="1")
    for _ in range(3):
        proc = subprocess.Popen([sys.executable, "-m", "orchestra", "topic", "pub", "-r", "50",
                                 "/chatter", "std_msgs/String", "hi"], env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            wait_for(lambda: _chatter_published(master.uri))
            os.kill(proc.pid, signal.SIGINT)
            os.kill(proc.pid, signal.SIGINT)
            _, err = proc.communicate(timeout=30)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        assert proc.returncode == 0 and "Traceback" not in err, err
        wait_for(lambda: not _chatter_published(master.uri))
