"""Fixes found by the real-ROS interop tests (tests/test_interop_ros1.py and
tests/test_interop_roscpp.py), pinned without ROS.

Each test reproduces what a real ROS 1 peer does on the wire with a small stand-in, so the
behaviour stays pinned on machines where Debian's ROS 1 is not installed.
"""
from __future__ import annotations

import socket
import threading
import xmlrpc.client
from xmlrpc.server import SimpleXMLRPCRequestHandler, SimpleXMLRPCServer

import pytest

from orchestra.node import introspect

pytestmark = pytest.mark.timeout(30)


class _RospyLikeSlave:
    """A slave API that, like rospy, closes its server while handling ``shutdown``.

    ``reply`` decides what ``shutdown`` does: "drop" (rospy: no reply, server gone),
    "refuse" (answers -1 and keeps serving), "drop_but_live" (drops the connection, keeps
    serving).
    """

    def __init__(self, reply: str, answers: dict | None = None):
        self.reply = reply
        self.answers = {"getPid": 4242, **(answers or {})}
        self.done = False
        owner = self

        class Handler(SimpleXMLRPCRequestHandler):
            def do_POST(self):  # noqa: N802 (http.server's name)
                body = self.rfile.read(int(self.headers["content-length"]))
                method = xmlrpc.client.loads(body)[1]
                if method == "shutdown" and owner.reply != "refuse":
                    self.close_connection = True
                    if owner.reply == "drop":
                        owner.done = True
                        self.server.socket.close()
                    return
                if method == "shutdown":
                    data = xmlrpc.client.dumps(([-1, "not now", 0],), methodresponse=True)
                else:
                    data = xmlrpc.client.dumps(([1, "", owner.answers[method]],),
                                               methodresponse=True)
                self.send_response(200)
                self.send_header("Content-Type", "text/xml")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data.encode())

            def log_message(self, *args):
                pass

        self.server = SimpleXMLRPCServer(("127.0.0.1", 0), Handler, logRequests=False)
        self.server.timeout = 0.05
        self.uri = f"http://127.0.0.1:{self.server.server_address[1]}/"
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while not self.done:
            try:
                self.server.handle_request()
            except (OSError, ValueError):
                return

    def close(self) -> None:
        self.done = True
        try:
            self.server.socket.close()
        except OSError:
            pass
        self.thread.join(2)


def _register(master, slave: _RospyLikeSlave) -> None:
    with xmlrpc.client.ServerProxy(master.uri) as proxy:
        assert proxy.registerPublisher("/victim", "/t", "std_msgs/String", slave.uri)[0] == 1


def test_kill_counts_a_node_that_drops_the_reply_and_goes_silent_as_killed(master):
    slave = _RospyLikeSlave("drop")
    try:
        _register(master, slave)
        introspect.kill_node(master.uri, "/victim")
        assert slave.done
    finally:
        slave.close()


@pytest.mark.parametrize("behaviour, settle", [
    ("refuse", None),          # the node refuses the shutdown
    ("drop_but_live", 0.3),    # the connection drops but the node keeps answering
])
def test_kill_fails_when_the_node_did_not_accept_the_shutdown(master, behaviour, settle):
    slave = _RospyLikeSlave(behaviour)
    extra = {} if settle is None else {"settle": settle}
    try:
        _register(master, slave)
        with pytest.raises(introspect.GraphError, match="did not accept"):
            introspect.kill_node(master.uri, "/victim", **extra)
    finally:
        slave.close()


def test_kill_of_a_node_that_no_longer_answers_names_it(master):
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        dead_uri = f"http://127.0.0.1:{sock.getsockname()[1]}/"
    with xmlrpc.client.ServerProxy(master.uri) as proxy:
        proxy.registerPublisher("/ghost", "/t", "std_msgs/String", dead_uri)
    with pytest.raises(introspect.GraphError, match=r"node \[/ghost\] does not answer"):
        introspect.kill_node(master.uri, "/ghost")


def test_echo_noarr_names_the_array_type_and_length_as_rostopic_does():
    from orchestra.node.cli import hide_arrays
    from orchestra.node.msg import get_message_class, to_yaml_text

    poses = get_message_class("geometry_msgs/PoseArray")()
    poses.poses = [get_message_class("geometry_msgs/Pose")()] * 2
    hide_arrays(poses)
    assert to_yaml_text(poses).endswith(
        '\nposes: "<array type: geometry_msgs/Pose, length: 2>"')
    # rostopic strips the brackets character-wise: a fixed array keeps "[36"
    pose = get_message_class("geometry_msgs/PoseWithCovariance")()
    hide_arrays(pose)
    assert pose.covariance == "<array type: float64[36, length: 36>"
    assert pose.pose.position.x == 0.0  # nested messages are left alone (top level only)


def test_node_info_names_inbound_peers_and_shows_rospy_socket_text_like_rosnode(
        master, monkeypatch, capsys):
    from orchestra.cli import main

    publisher = _RospyLikeSlave("drop")
    listener = _RospyLikeSlave("drop", {"getBusInfo": [
        [1, publisher.uri, "i", "TCPROS", "/t", True,
         "TCPROS connection on port 4000 to [127.0.0.1:5000 on socket 9]"],
        [2, "/gone", "i", "TCPROS", "/t", False, ""],
        [3, "/late", "o", "TCPROS", "/t", True]]})
    try:
        with xmlrpc.client.ServerProxy(master.uri) as proxy:
            proxy.registerPublisher("/talker", "/t", "std_msgs/String", publisher.uri)
            proxy.registerSubscriber("/listener", "/t", "std_msgs/String", listener.uri)
        monkeypatch.setenv("ROS_MASTER_URI", master.uri)
        with pytest.raises(SystemExit) as info:
            main(["node", "info", "/listener"])
        assert info.value.code == 0
        out = capsys.readouterr().out
        assert out.endswith(
            "Pid: 4242\nConnections:\n"
            " * topic: /t\n"
            f"    * to: /talker ({publisher.uri})\n"
            "    * direction: inbound (4000 - 127.0.0.1:5000) [9]\n"
            "    * transport: TCPROS\n"
            " * topic: /t\n"
            "    * to: /late\n"
            "    * direction: outbound\n"
            "    * transport: TCPROS\n"
            "\n")
    finally:
        publisher.close()
        listener.close()


def test_a_signal_arriving_while_shutdown_starts_does_not_deadlock(monkeypatch):
    """Found by killing nodes right as they exited: the SIGINT handler re-entered
    signal_shutdown() on the thread that was inside it and waited for its own lock."""
    from orchestra.node import runtime

    rt = runtime.NodeRuntime("/n", "/", "http://127.0.0.1:9/", {}, "127.0.0.1", [])
    started = []

    class SignalDuringStart(threading.Thread):
        def start(self):
            rt.signal_shutdown("signal SIGINT")  # what the handler does, same thread
            started.append(self)
            super().start()

    monkeypatch.setattr(runtime.threading, "Thread", SignalDuringStart)
    caller = SignalDuringStart.__mro__[1](target=rt.signal_shutdown, args=("process exit",), daemon=True)
    caller.start()
    caller.join(5)
    assert not caller.is_alive(), "signal_shutdown deadlocked"
    assert len(started) == 1 and rt.is_shutdown()
    rt.wait_shutdown_done(5)


EXITING_NODE = """
import json, sys, time
import orchestra.node as rospy
rospy.init_node("leaver")
from orchestra.node.msg import get_message_class
rospy.Publisher("chatter", get_message_class("std_msgs/String"))
def slow_hook():                              # a slow hook: the exit takes a while
    print(json.dumps({"hook": True}), flush=True)
    time.sleep(1.0)
rospy.on_shutdown(slow_hook)
print(json.dumps({"ready": True}), flush=True)
sys.stdin.readline()                          # the script ends when the test says so
print(json.dumps({"ending": True}), flush=True)
"""


def test_sigint_while_a_finished_script_unregisters_does_not_leave_it_registered(
        master, tmp_path):
    import os
    import signal
    import subprocess
    import sys

    script = tmp_path / "leaver.py"
    script.write_text(EXITING_NODE)
    env = dict(os.environ, ROS_MASTER_URI=master.uri, PYTHONUNBUFFERED="1")
    with subprocess.Popen([sys.executable, str(script)], env=env, stdin=subprocess.PIPE,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) as proc:
        try:
            assert "ready" in proc.stdout.readline()
            proc.stdin.write("\n")
            proc.stdin.flush()
            assert "ending" in proc.stdout.readline()
            assert "hook" in proc.stdout.readline()     # inside the slow hook, at exit
            proc.send_signal(signal.SIGINT)
            proc.send_signal(signal.SIGINT)
            assert proc.wait(10) == 0, proc.stderr.read()
            with xmlrpc.client.ServerProxy(master.uri) as proxy:
                pubs = proxy.getSystemState("/probe")[2][0]
            assert not [t for t, nodes in pubs if "/leaver" in nodes]
        finally:
            if proc.poll() is None:
                proc.kill()


def test_bus_info_describes_the_socket_as_rospy_does():
    from orchestra.node.topics import describe_socket

    with socket.create_server(("127.0.0.1", 0)) as server:
        client = socket.create_connection(server.getsockname())
        accepted, _ = server.accept()
        try:
            port, peer = accepted.getsockname()[1], client.getsockname()
            assert describe_socket(accepted) == (
                f"TCPROS connection on port {port} to [{peer[0]}:{peer[1]} on socket "
                f"{accepted.fileno()}]")
        finally:
            client.close()
            accepted.close()
    assert describe_socket(accepted) == "" and describe_socket(None) == ""


def test_string_arrays_print_as_indented_yaml_block_lists_like_genpy():
    """Found calling roscpp's mux/list: `orchestra service call` printed
    ``topics: - /a\n- /b`` (not even YAML); rosservice (genpy) prints a block list indented
    at the field's level, nested ones too."""
    from orchestra.node.msg import get_message_class, message_class_from_definition, to_yaml_text

    listing = message_class_from_definition("test_msgs/Topics", "string[] topics\n")
    assert to_yaml_text(listing(topics=["/a", "/b c", ""])) == \
        "topics: \n  - /a\n  - /b c\n  - ''"
    log = get_message_class("rosgraph_msgs/Log")(name="/n", topics=["/rosout", "/x"])
    assert "\ntopics: \n  - /rosout\n  - /x" in to_yaml_text(log)
    outer = message_class_from_definition(
        "test_msgs/Outer", "test_msgs/Topics inner\n"
        "================================================================================\n"
        "MSG: test_msgs/Topics\nstring[] topics\n")
    assert to_yaml_text(outer(inner=listing(topics=["/a"]))) == \
        "inner: \n  topics: \n    - /a"


def test_a_latched_message_that_arrives_before_the_callback_is_added_is_not_lost():
    """Found with roscpp's topic_tools/mux: /mux/selected (latched) sometimes never reached an
    orchestra subscriber. The reader thread connects as soon as the master answers, before the
    Subscriber adds its callback, and roscpp sends the latched message right behind its
    header: delivered to no callback, it was gone. rospy keeps the newest message of each
    latched connection and gives it to callbacks added later; so does orchestra now, once."""
    from orchestra.node.msg import get_message_class
    from orchestra.node.topics import InConnection, Subscription

    string = get_message_class("std_msgs/String")
    sub = Subscription(None, "/mux/selected", string, 10)
    conn = InConnection(sub, "http://127.0.0.1:9/")  # never started: the test feeds it
    conn.header = {"latching": "1", "callerid": "/mux", "md5sum": string._md5sum}
    sub.connections[conn.uri] = conn
    sub.deliver_raw(bytes(string(data="/a").serialize_bytes()), conn.header, conn.uri, conn)
    got = []
    sub.add_callback(lambda m: got.append(m.data), None, string)
    assert got == ["/a"]
    sub.deliver_raw(bytes(string(data="/b").serialize_bytes()), conn.header, conn.uri, conn)
    assert got == ["/a", "/b"]
    later = []
    sub.add_callback(lambda m, tag: later.append((tag, m.data)), "late", string)
    assert later == [("late", "/b")] and got == ["/a", "/b"]
    # a publisher that does not latch leaves nothing to replay
    plain = Subscription(None, "/chatter", string, 10)
    other = InConnection(plain, "http://127.0.0.1:9/")
    other.header = {"latching": "0"}
    plain.connections[other.uri] = other
    plain.deliver_raw(bytes(string(data="x").serialize_bytes()), other.header, other.uri, None)
    plain.add_callback(lambda m: later.append(m.data), None, string)
    assert later == [("late", "/b")]


LATCHED_TWICE = """
import json, threading, time
import orchestra.node as rospy
from orchestra.node.msg import get_message_class
S = get_message_class("std_msgs/String")
rospy.init_node("latch_twice")
pub = rospy.Publisher("/latched", S, latch=True, queue_size=1)
pub.publish(S(data="kept"))
got, first, second = [], threading.Event(), threading.Event()
rospy.Subscriber("/latched", S, lambda m: (got.append(["a", m.data]), first.set()))
first.wait(10)
rospy.Subscriber("/latched", S, lambda m: (got.append(["b", m.data]), second.set()))
second.wait(5)
time.sleep(0.2)
print(json.dumps(got), flush=True)
"""


def test_a_second_subscriber_to_a_latched_topic_gets_the_latched_message(master, tmp_path):
    """rospy gives a new Subscriber on an already connected latched topic the latched
    message at once; orchestra shared the connection but gave the new callback nothing."""
    import json
    import os
    import subprocess
    import sys

    script = tmp_path / "latch_twice.py"
    script.write_text(LATCHED_TWICE)
    env = dict(os.environ, ROS_MASTER_URI=master.uri, PYTHONUNBUFFERED="1")
    done = subprocess.run([sys.executable, str(script)], env=env, capture_output=True,
                          text=True, timeout=25)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == [["a", "kept"], ["b", "kept"]]
